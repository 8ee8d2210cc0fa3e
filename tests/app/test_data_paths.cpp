// Where the program finds its shipped data, tried on copies of the built binary in fresh prefixes:
// beside itself (<prefix>/share/anatomy-tutor), AT_DATA_DIR over that, and a one-line error that
// names the folder when neither has it. The copies never see the source tree's data/.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <string>
#include <sys/wait.h>

#include "test_support.h"

namespace fs = std::filesystem;

namespace {

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

// <root>/bin/anatomy-tutor, a copy of the built binary.
fs::path copyBinary(const fs::path& root) {
  fs::create_directories(root / "bin");
  const fs::path binary = root / "bin" / "anatomy-tutor";
  fs::copy_file(at::test::appBinary(), binary);
  return binary;
}

// <dir>/courses/temporal_bone.json with its title changed to `title`, so that a listing shows
// which copy was read.
void writeCourses(const fs::path& dir, const std::string& title) {
  fs::create_directories(dir / "courses");
  std::string json = at::test::readFile(at::test::sourceDir() / "data" / "courses" / "temporal_bone.json");
  const std::string key = "\"title\": \"";
  const std::size_t at = json.find(key);
  REQUIRE(at != std::string::npos);
  const std::size_t end = json.find('"', at + key.size());
  json.replace(at + key.size(), end - at - key.size(), title);
  std::ofstream(dir / "courses" / "temporal_bone.json") << json;
}

// Runs `binary args` from `cwd` with a clean environment: no AT_DATA_DIR unless `dataDir` is given.
at::test::CommandResult runCopy(const fs::path& binary, const std::string& args, const fs::path& cwd,
                                const std::string& dataDir = "") {
  at::test::TempDir out("at-copy");
  const std::string env = "env -i PATH=/usr/bin:/bin HOME=" + quoted(cwd) +
                          (dataDir.empty() ? std::string() : " AT_DATA_DIR=" + quoted(fs::path(dataDir)));
  const std::string cmd = "cd " + quoted(cwd) + " && " + env + " " + quoted(binary) + " " + args + " >" +
                          quoted(out / "o") + " 2>" + quoted(out / "e") + " </dev/null";
  const int status = std::system(cmd.c_str());
  at::test::CommandResult r;
  r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = at::test::readFile(out / "o");
  r.err = at::test::readFile(out / "e");
  return r;
}

}  // namespace

TEST_CASE("a copy of the program in a fresh prefix reads the courses and presets installed beside it") {
  if (!at::test::requireAppBinary("the data-path test")) return;
  at::test::TempDir root("at-prefix");
  const fs::path binary = copyBinary(root.path());
  const fs::path share = root / "share" / "anatomy-tutor";
  writeCourses(share, "Installed copy of the temporal bone");
  fs::copy(at::test::sourceDir() / "data" / "presets", share / "presets", fs::copy_options::recursive);

  auto r = runCopy(binary, "courses --db " + quoted(root / "a.db"), root.path());
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("Installed copy of the temporal bone") != std::string::npos);

  const fs::path png = root / "cochlea.png";
  r = runCopy(binary, "render phantom:32 cochlea --mode bare --size 32x24 --out " + quoted(png), root.path());
  if (r.exitCode != 0 && r.err.find("EGL") != std::string::npos) {
    at::test::skipf("rendering from the installed presets needs EGL (%s)", r.err.c_str());
  } else {
    CHECK_MESSAGE(r.exitCode == 0, r.err);
    CHECK(r.out.find("preset cochlea_bare") != std::string::npos);
  }
}

TEST_CASE("AT_DATA_DIR overrides the installed courses, and what it lacks still comes from beside the program") {
  if (!at::test::requireAppBinary("the AT_DATA_DIR test")) return;
  at::test::TempDir root("at-prefix");
  const fs::path binary = copyBinary(root.path());
  writeCourses(root / "share" / "anatomy-tutor", "Installed copy");
  fs::copy(at::test::sourceDir() / "data" / "presets", root / "share" / "anatomy-tutor" / "presets", fs::copy_options::recursive);
  const fs::path override = root / "override";
  writeCourses(override, "Overriding copy");

  auto r = runCopy(binary, "courses --db " + quoted(root / "a.db"), root.path(), override.string());
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("Overriding copy") != std::string::npos);
  CHECK(r.out.find("Installed copy") == std::string::npos);
  // No presets in the override: render still finds the installed ones.
  r = runCopy(binary, "render phantom:32 cochlea --mode bare --size 32x24 --out " + quoted(root / "c.png"), root.path(),
              override.string());
  if (r.exitCode != 0 && r.err.find("EGL") != std::string::npos) return;
  CHECK_MESSAGE(r.exitCode == 0, r.err);
}

TEST_CASE("a copy of the program with no data beside it says in one line where it looked, and creates no database") {
  if (!at::test::requireAppBinary("the missing-data test")) return;
  at::test::TempDir root("at-prefix");
  const fs::path binary = copyBinary(root.path());
  const auto r = runCopy(binary, "courses --db " + quoted(root / "a.db"), root.path());
  CHECK(r.exitCode != 0);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK(r.err.find("no course folder at " + (root / "share" / "anatomy-tutor" / "courses").string()) != std::string::npos);
  CHECK(r.err.find("AT_DATA_DIR") != std::string::npos);
  CHECK_FALSE(fs::exists(root / "a.db"));
}
