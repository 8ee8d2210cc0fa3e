// Course packages from anyone, built as an attacker would (a legitimate export, altered, every
// checksum recomputed): a dataset name that is a path, a dot, a separator or a look-alike is
// refused before anything is touched, and nothing outside the data folder changes; a package's
// presets are stored for its course only, so shipped lessons keep their views.
#include <doctest/doctest.h>

#include <algorithm>
#include <fstream>

#include "cli_checks.h"
#include "course_import_fixtures.h"
#include "course_views.h"
#include "data_paths.h"
#include "db/connection.h"
#include "db/preset_store.h"
#include "package_forgery.h"
#include "render/preset.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

// The package with its course renamed to `courseId` (lesson and question ids follow, so the course
// fits beside ear_tour) and its dataset renamed to `dataset`.
fs::path renamedCourse(const fs::path& package, const fs::path& out, const std::string& courseId, const std::string& dataset) {
  return test::forgePackage(package, out, [&](auto& entries, nlohmann::json& manifest, nlohmann::json& course) {
    std::string text = course.dump();
    for (std::size_t at = 0; (at = text.find("ear_tour", at)) != std::string::npos; at += courseId.size())
      text.replace(at, 8, courseId);
    course = nlohmann::json::parse(text);
    course["dataset"] = dataset;
    manifest["course"]["id"] = courseId;
    manifest["dataset"]["name"] = dataset;
    (void)entries;
  });
}

}  // namespace

TEST_CASE("CourseImport_HostileDatasetNames_AreRefusedAndNothingOutsideTheDataFolderChanges") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author"), home("at-home");
  const fs::path package = author / "ear.atcourse";
  test::exportEarTour(author.path(), package);
  // The student's folder: the database, its data folder, and folders an attacker aims at.
  const fs::path student = home / "student";
  fs::create_directories(student);
  const fs::path db = student / "s.db";
  auto first = test::runApp("course import " + test::quotedPath(package) + " --db " + test::quotedPath(db));
  REQUIRE_MESSAGE(first.exitCode == 0, first.err);
  for (const char* victim : {"victim", "student/victim2", "student/s-data/victim3"}) {
    fs::create_directories(home / victim);
    std::ofstream(home / victim / "keep.txt") << "the user's file in " << victim;
  }
  const std::string courses = test::runApp("course list --db " + test::quotedPath(db)).out;
  const auto before = test::snapshotTree(home.path(), {"student/s.db"});

  const std::string hostile[] = {(home / "victim").string(), "../../victim2", "../victim3", "../../../x", ".", "..", "a/b",
                                 "-rf", ".hidden", "ear_l\xd0\xb0" "b" /* Cyrillic a */, "e\xcc\x81" "ar" /* combining accent */,
                                 std::string(65, 'a')};
  int n = 0;
  for (const std::string& name : hostile) {
    CAPTURE(name);
    const fs::path forged = renamedCourse(package, author / ("hostile" + std::to_string(n) + ".atcourse"), "hostile" + std::to_string(n), name);
    ++n;
    auto r = test::runApp("course import " + test::quotedPath(forged) + " --db " + test::quotedPath(db));
    test::checkOneLineError(r, "dataset.name");
    CHECK(test::snapshotTree(home.path(), {"student/s.db"}) == before);
    CHECK(test::runApp("course list --db " + test::quotedPath(db)).out == courses);
  }
  CHECK(test::importedDatasetNames(db) == std::vector<std::string>{"ear_lab"});
  // The course imported first still plays: its dataset's files were not touched.
  auto structures = test::runApp("structures ear_lab --db " + test::quotedPath(db));
  CHECK_MESSAGE(structures.exitCode == 0, structures.err);

  SUBCASE("import --name takes the same rule") {
    for (const std::string& name : {std::string("../x"), std::string("a/b"), std::string("."), std::string("-rf")}) {
      auto r = test::runApp("import --volume " + test::quotedPath(author / "volume.nrrd") + " --name " + test::quotedPath(name) +
                            " --db " + test::quotedPath(db));
      test::checkOneLineError(r, "dataset name '");
    }
    CHECK(test::importedDatasetNames(db) == std::vector<std::string>{"ear_lab"});
  }
}

TEST_CASE("CourseImport_PackagePresets_AreStoredForTheirCourseAndNeverReplaceAShippedOne") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author"), student("at-student");
  const fs::path package = author / "ear.atcourse";
  test::exportEarTour(author.path(), package);
  const render::PresetLibrary library(app::dataSubdirectory("presets"));
  auto shipped = library.load("cochlea_wdt");
  REQUIRE(shipped);
  auto bare = library.load("cochlea_bare");
  REQUIRE(bare);
  REQUIRE(render::presetToJson(*bare) != render::presetToJson(*shipped));
  // "Another course" carries presets/cochlea_wdt.json — the bare cochlea — and shows it.
  const fs::path forged = test::forgePackage(package, author / "collide.atcourse", [&](auto& entries, nlohmann::json&, nlohmann::json& course) {
    course["lessons"][0]["steps"][0]["preset"] = "cochlea_wdt";
    if (test::TarEntry* e = test::findEntry(entries, "presets/cochlea_wdt.json")) e->data = render::presetToJson(*bare);
    else entries.push_back(test::TarEntry("presets/cochlea_wdt.json", render::presetToJson(*bare)));
  });
  const fs::path db = student / "s.db";
  auto r = test::runApp("course import " + test::quotedPath(forged) + " --db " + test::quotedPath(db));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("stored for this course only (") != std::string::npos);
  CHECK(r.out.find("ear_tour/cochlea_wdt") != std::string::npos);

  auto database = db::openDatabase(db.string());
  REQUIRE(database);
  auto plain = db::findPreset(*database, "cochlea_wdt");
  REQUIRE(plain);
  CHECK_FALSE(plain->has_value());  // nothing stands in for the shipped preset
  const render::IntensityLevels levels{};
  // The shipped lessons' step "cochlea_wdt" still draws the shipped WDT preset…
  auto shown = app::presetForStep(library, "cochlea", "cochlea_wdt", levels, &database->get());
  REQUIRE(shown);
  CHECK(render::presetToJson(*shown) == render::presetToJson(*shipped));
  // …and the imported course's step draws its own.
  auto course = test::runApp("course export ear_tour --out " + test::quotedPath(student / "again.atcourse") + " --db " +
                             test::quotedPath(db));
  REQUIRE_MESSAGE(course.exitCode == 0, course.err);
  auto own = app::presetForStep(library, "cochlea", "ear_tour/cochlea_wdt", levels, &database->get());
  REQUIRE(own);
  CHECK(render::presetToJson(*own) == render::presetToJson(*bare));
  // Exported again, the preset travels under its package name.
  auto entries = test::readTar(student / "again.atcourse");
  CHECK(test::findEntry(entries, "presets/cochlea_wdt.json") != nullptr);
  const auto again = nlohmann::json::parse(test::findEntry(entries, "course.json")->data);
  CHECK(again["lessons"][0]["steps"][0]["preset"] == "cochlea_wdt");
}

TEST_CASE("CourseImport_WhitespacePaddedPresets_GrowTheDatabaseOnlyByTheirContent") {
  if (!test::requireAppBinary("course packages")) return;
  test::TempDir author("at-author"), student("at-student");
  const fs::path package = author / "ear.atcourse";
  test::exportEarTour(author.path(), package);
  const render::PresetLibrary library(app::dataSubdirectory("presets"));
  const std::string compact = render::presetToJson(*library.load("cochlea_wdt"));
  const std::string padding(28 << 10, ' ');  // twice, under the 64 KiB a preset may hold
  const fs::path padded = test::forgePackage(package, author / "padded.atcourse", [&](auto& entries, nlohmann::json&, nlohmann::json&) {
    for (int i = 0; i < 64; ++i) entries.push_back(test::TarEntry("presets/p" + std::to_string(i) + ".json", padding + compact + padding));
  });
  const fs::path db = student / "s.db";
  REQUIRE(test::runApp("course list --db " + test::quotedPath(db)).exitCode == 0);
  auto r = test::runApp("course import " + test::quotedPath(padded) + " --db " + test::quotedPath(db));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  auto database = db::openDatabase(db.string());
  REQUIRE(database);
  for (int i = 0; i < 64; ++i) {
    auto p = db::findPreset(*database, "ear_tour/p" + std::to_string(i));
    REQUIRE(p);
    REQUIRE(p->has_value());
    CHECK((*p)->json.size() <= compact.size() + 16);  // the padding is not stored
  }
}
