// A course import is all or nothing: killed (SIGKILL) at each point of its work — after
// extracting, before the commit, inside the transaction, after the commit — the database holds
// the whole course, dataset and presets or none of them, and once the program starts again no
// staging folder is left and the stored dataset's files are in place. On a full disk the import
// is refused and keeps nothing.
#include <doctest/doctest.h>

#include <sys/mount.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

#include "cli_checks.h"
#include "test_support.h"
#include "course_import_fixtures.h"
#include "data_paths.h"
#include "db/connection.h"
#include "db/dataset_store.h"
#include "db/preset_store.h"
#include "package_forgery.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

struct StoredState {
  bool course = false, dataset = false;
  std::size_t presets = 0;
};

StoredState storedState(const fs::path& db) {
  StoredState s;
  auto listed = test::runApp("course list --db " + test::quotedPath(db));
  REQUIRE_MESSAGE(listed.exitCode == 0, listed.err);
  s.course = listed.out.find("ear_tour") != std::string::npos;
  auto names = test::importedDatasetNames(db);
  s.dataset = std::find(names.begin(), names.end(), "ear_lab") != names.end();
  auto database = db::openDatabase(db.string());
  REQUIRE(database);
  auto presets = db::listPresets(*database);
  REQUIRE(presets);
  s.presets = presets->size();
  return s;
}

std::vector<fs::path> stagingFolders(const fs::path& dataFolder) {
  std::vector<fs::path> out;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dataFolder, ec))
    if (e.path().filename().string().rfind("staging-", 0) == 0) out.push_back(e.path());
  return out;
}

// A package of ear_tour with one preset of its own (so presets are part of what must be whole).
fs::path packageWithPreset(const fs::path& package, const fs::path& out) {
  return test::forgePackage(package, out, [](auto& entries, nlohmann::json&, nlohmann::json& course) {
    course["lessons"][0]["steps"][0]["preset"] = "own_view";
    entries.push_back(test::TarEntry("presets/own_view.json", test::readFile(app::dataSubdirectory("presets") / "cochlea_bare.json")));
  });
}

}  // namespace

TEST_CASE("CourseImport_KilledAtAnyPoint_LeavesTheOldStateOrTheNewOne") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author");
  test::exportEarTour(author.path(), author / "ear.atcourse");
  const fs::path withPreset = packageWithPreset(author / "ear.atcourse", author / "own.atcourse");
  std::size_t packagedPresets = 0;
  for (const auto& e : test::readTar(withPreset)) packagedPresets += e.name.rfind("presets/", 0) == 0;
  REQUIRE(packagedPresets > 1);

  for (const char* point : {"extracted", "before-commit", "in-transaction", "after-commit"}) {
    CAPTURE(point);
    test::TempDir student("at-student");
    const fs::path db = student / "s.db", data = student / "s-data";
    REQUIRE(test::runApp("course list --db " + test::quotedPath(db)).exitCode == 0);
    ::setenv("AT_TEST_IMPORT_KILL_AT", point, 1);
    auto killed = test::runApp("course import " + test::quotedPath(withPreset) + " --db " + test::quotedPath(db));
    ::unsetenv("AT_TEST_IMPORT_KILL_AT");
    CHECK(killed.exitCode != 0);
    CHECK(killed.out.empty());
    // The rows: all or none (storedState's commands also open the database: the next start).
    const StoredState s = storedState(db);
    const bool committed = std::string(point) == "after-commit";
    CHECK(s.course == committed);
    CHECK(s.dataset == committed);
    CHECK(s.presets == (committed ? packagedPresets : 0u));
    // The next start finished or removed what the killed import left.
    CHECK(stagingFolders(data).empty());
    CHECK(fs::exists(data / "datasets" / "ear_lab" / "volume.nrrd") == committed);
    if (committed) {
      auto play = test::runApp("structures ear_lab --db " + test::quotedPath(db));
      CHECK_MESSAGE(play.exitCode == 0, play.err);
    } else {
      // Nothing of it stays in the way: the same import now succeeds.
      auto again = test::runApp("course import " + test::quotedPath(withPreset) + " --db " + test::quotedPath(db));
      CHECK_MESSAGE(again.exitCode == 0, again.err);
      CHECK(again.out.find("version 1: added") != std::string::npos);
    }
  }
}

TEST_CASE("CourseImport_OnAFullDisk_IsRefusedAndKeepsNothing") {
  if (::geteuid() != 0) {
    at::test::skipf("a full disk is made with a small tmpfs, which only root may mount");
    return;
  }
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author"), student("at-student");
  // A 96³ volume (1.7 MB as int16, plus its labels) for a 1 MiB disk that holds the database.
  test::exportEarTour(author.path(), author / "ear.atcourse", 96);
  const fs::path disk = student / "disk";
  fs::create_directories(disk);
  if (::mount("tmpfs", disk.c_str(), "tmpfs", 0, "size=1m") != 0) {
    at::test::skipf("mounting a tmpfs failed here (%s)", std::strerror(errno));
    return;
  }
  struct Unmount {
    fs::path at;
    ~Unmount() { ::umount2(at.c_str(), MNT_DETACH); }
  } unmount{disk};
  const fs::path db = disk / "s.db";
  REQUIRE(test::runApp("course list --db " + test::quotedPath(db)).exitCode == 0);
  const StoredState before = storedState(db);
  auto r = test::runApp("course import " + test::quotedPath(author / "ear.atcourse") + " --db " + test::quotedPath(db));
  test::checkOneLineError(r, "disk full");
  const StoredState after = storedState(db);
  CHECK(after.course == before.course);
  CHECK_FALSE(after.dataset);
  CHECK(after.presets == before.presets);
  CHECK(stagingFolders(disk / "s-data").empty());
  CHECK_FALSE(fs::exists(disk / "s-data" / "datasets" / "ear_lab"));
}
