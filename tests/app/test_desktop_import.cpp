// Importing a dataset from the desktop app and seeing it in the view: a scripted run under Xvfb
// (Mesa). The import's other paths (failures, cancel) run without a window in
// test_desktop_long_work.cpp.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <vector>

#include <nlohmann/json.hpp>

#include "desktop_script.h"
#include "cli_checks.h"
#include "test_support.h"
#include "volume/png_image.h"

namespace fs = std::filesystem;
using at::test::TempDir;
using json = nlohmann::json;

namespace {

using Run = at::test::DesktopRun;
using at::test::eventsOf;

// Runs the desktop app on `script` under xvfb-run with the database `db`, in a small window with a
// coarse volume image (software GL on two shared cores is slow).
Run runDesktop(const TempDir& dir, const json& script, const fs::path& db, const std::string& dataset = "phantom:128",
               const std::string& screenshot = "") {
  at::test::DesktopOptions options;
  options.dataset = dataset;
  options.db = db;
  options.screenshot = screenshot;
  return at::test::runDesktopScript(dir, script, options);
}

}  // namespace

TEST_CASE("ImportInTheApp_AbdominalCt_StoresItReportsEachStageAndOpensItInTheExploreView") {
  if (!at::test::requireXvfb()) return;
  if (!at::test::requireSharedData("desktop import")) return;
  TempDir dir("desktop-import");
  const fs::path db = dir / "t.db", shot = dir / "abdomen.png";
  const auto ts = at::test::sharedData("totalsegmentator");
  const json script = {{"actions",
                        {{{"do", "import"},
                          {"volume", (ts / "ct_small.nii.gz").string()},
                          {"labels", (ts / "seg_small.nii.gz").string()},
                          {"names", (ts / "labels.json").string()},
                          {"name", "abdomen"}},
                         {{"do", "open_imported"}},
                         {{"do", "select"}, {"structure", "liver"}},
                         {{"do", "wait_field"}}}}};
  const Run r = runDesktop(dir, script, db, "phantom:128", shot.string());
  INFO(r.err);
  REQUIRE(r.exitCode == 0);

  std::vector<std::string> stages;
  for (const json& e : eventsOf(r, "import_progress"))
    if (stages.empty() || stages.back() != e.at("stage")) stages.push_back(e.at("stage"));
  CHECK(stages == std::vector<std::string>{"checking", "loading volume", "loading labels", "checking alignment",
                                           "checksums", "storing"});
  const auto done = eventsOf(r, "import_done");
  REQUIRE(done.size() == 1);
  CHECK(done[0].at("structures") == 41);
  CHECK(done[0].at("dims") == json::array({122, 101, 30}));
  CHECK(eventsOf(r, "import_failed").empty());

  // Opened in the explore view: the dataset event, then a structure only the abdomen has.
  const auto opened = eventsOf(r, "dataset");
  REQUIRE(opened.size() == 1);
  CHECK(opened[0].at("dataset") == "abdomen");
  CHECK(opened[0].at("structures") == 41);
  const auto selected = eventsOf(r, "select");
  REQUIRE(!selected.empty());
  CHECK(selected.back().at("structure") == "liver");
  bool liverField = false;
  for (const json& e : eventsOf(r, "field")) liverField = liverField || e.at("structure") == "liver";
  CHECK(liverField);

  // The view shows the new volume: a good part of it is not background.
  auto img = at::readPng(shot.string());
  REQUIRE(img);
  int lit = 0;
  for (int y = 0; y < img->height; ++y)
    for (int x = 320; x < img->width; ++x) {
      const std::uint8_t* p = img->pixel(x, y);
      if (p[0] + p[1] + p[2] > 3 * 24) ++lit;
    }
  CHECK(lit > (800 - 320) * 480 / 10);

  // The command line sees what the app stored, and opens it by name.
  CHECK(at::test::importedDatasetNames(db) == std::vector<std::string>{"abdomen"});
  auto structures = at::test::runApp("structures abdomen --db '" + db.string() + "'");
  CHECK(structures.exitCode == 0);
  CHECK(structures.out.find("liver") != std::string::npos);

  // And the desktop opens it by name next time.
  const Run again = runDesktop(dir, {{"actions", {{{"do", "select"}, {"structure", "spleen"}}}}}, db, "abdomen");
  INFO(again.err);
  CHECK(again.exitCode == 0);
  const auto spleen = eventsOf(again, "select");
  REQUIRE(spleen.size() == 1);
  CHECK(spleen[0].at("structure") == "spleen");
}

