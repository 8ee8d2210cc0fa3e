// Long work and failures in the desktop app (issue 7): importing a dataset from the app with
// progress and cancel, a file that does not load, and cancelling a full-resolution CPU field.
// Scripted runs under Xvfb (Mesa), each with its own database in a TempDir.
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

// The names of the imported datasets in `db`, through `anatomy-tutor datasets --json`.
std::vector<std::string> importedNames(const fs::path& db) {
  auto listed = at::test::runApp("datasets --json --db '" + db.string() + "'");
  REQUIRE_MESSAGE(listed.exitCode == 0, listed.err);
  const json all = json::parse(listed.out);
  std::vector<std::string> names;
  for (const json& d : all.at("datasets"))
    if (!d.value("builtin", true)) names.push_back(d.at("id").get<std::string>());
  return names;
}

bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
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
  CHECK(importedNames(db) == std::vector<std::string>{"abdomen"});
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

TEST_CASE("ImportInTheApp_FileThatDoesNotLoad_ShowsTheLoadersMessageStoresNothingAndTheAppKeepsWorking") {
  if (!at::test::requireXvfb()) return;
  TempDir dir("desktop-import-broken");
  const fs::path db = dir / "t.db", broken = dir / "broken.nii";
  std::ofstream(broken) << "not a NIfTI image: a few bytes of plain text\n";
  const json script = {{"actions",
                        {{{"do", "import"}, {"volume", broken.string()}, {"name", "broken"}},
                         {{"do", "import"}, {"volume", broken.string()}, {"name", ""}},
                         {{"do", "import"}, {"volume", (dir / "missing.nii.gz").string()}, {"name", "missing"}},
                         // The app keeps working: select, hover, render.
                         {{"do", "select"}, {"structure", "vestibule"}},
                         {{"do", "hover_structure"}, {"structure", "cochlea"}},
                         {{"do", "wait_field"}}}}};
  const Run r = runDesktop(dir, script, db, "phantom:128", (dir / "after.png").string());
  INFO(r.err);
  REQUIRE(r.exitCode == 0);
  const auto failed = eventsOf(r, "import_failed");
  REQUIRE(failed.size() == 3);
  // The loader's one-line message, naming the file.
  const std::string message = failed[0].at("message");
  CHECK(message.find(broken.string()) != std::string::npos);
  CHECK(message.find('\n') == std::string::npos);
  CHECK(failed[1].at("message").get<std::string>().find("name") != std::string::npos);
  CHECK(failed[2].at("message").get<std::string>().find("missing.nii.gz: no such file") != std::string::npos);
  // The message reaches the app's message list (printed to stderr as it is shown).
  CHECK(r.err.find("import: " + message) != std::string::npos);
  CHECK(eventsOf(r, "import_done").empty());
  CHECK(!eventsOf(r, "field").empty());
  CHECK(fs::exists(dir / "after.png"));
  CHECK(importedNames(db).empty());

  // A scripted cancel_at must name a stage.
  const Run bad = runDesktop(dir, {{"actions", {{{"do", "import"}, {"volume", broken.string()}, {"name", "x"}, {"cancel_at", "later"}}}}},
                             db);
  CHECK(bad.exitCode == 2);
  CHECK(bad.err.find("cancel_at") != std::string::npos);
}

TEST_CASE("ImportInTheApp_Cancelled_StoresNothingAndTheNameStaysFree") {
  if (!at::test::requireXvfb()) return;
  if (!at::test::requireSharedData("desktop import cancel")) return;
  TempDir dir("desktop-import-cancel");
  const fs::path db = dir / "t.db";
  const auto ts = at::test::sharedData("totalsegmentator");
  const json ct = (ts / "ct_small.nii.gz").string(), seg = (ts / "seg_small.nii.gz").string();
  // All four use one name: had a cancelled import stored anything, the last would be refused.
  const json script = {
      {"actions",
       {// Cancelled right after it starts, the way the Cancel button does (a DICOM series: the slowest input).
        {{"do", "import"}, {"volume", (ts / "ct_dicom").string()}, {"labels", (ts / "seg_dicom.nii.gz").string()},
         {"name", "abdomen"}, {"wait", false}},
        {{"do", "cancel_import"}},
        // Cancelled inside the volume loader, and after everything but storing.
        {{"do", "import"}, {"volume", ct}, {"labels", seg}, {"name", "abdomen"}, {"cancel_at", "loading volume"}},
        {{"do", "import"}, {"volume", ct}, {"labels", seg}, {"name", "abdomen"}, {"cancel_at", "checksums"}},
        {{"do", "import"}, {"volume", ct}, {"labels", seg}, {"name", "abdomen"}}}}};
  const Run r = runDesktop(dir, script, db);
  INFO(r.err);
  REQUIRE(r.exitCode == 0);
  CHECK(eventsOf(r, "import_started").size() == 4);
  CHECK(eventsOf(r, "import_cancelled").size() == 3);
  CHECK(eventsOf(r, "import_failed").empty());
  const auto done = eventsOf(r, "import_done");
  REQUIRE(done.size() == 1);
  CHECK(done[0].at("structures") == 41);
  // The last cancelled import had reached its checksums before it stopped.
  std::vector<std::string> stages;
  bool afterSecondCancel = false;
  int cancels = 0;
  for (const json& e : r.events) {
    if (e.value("event", "") == "import_cancelled") afterSecondCancel = ++cancels == 2;
    if (afterSecondCancel && e.value("event", "") == "import_progress") stages.push_back(e.at("stage"));
  }
  CHECK(contains(stages, "checksums"));
  CHECK(!contains(stages, "storing"));
  CHECK(importedNames(db) == std::vector<std::string>{"abdomen"});
}

TEST_CASE("StudyExport_CancelledPartWay_StopsAndLeavesNoPartialSetBehind") {
  if (!at::test::requireXvfb()) return;
  TempDir dir("desktop-export-cancel");
  std::ifstream in(at::test::sourceDir() / "data" / "studies" / "paper_survey.json");
  const std::string studyId = json::parse(in).at("id");
  const fs::path out = dir / "export";
  const json script = {{"actions",
                        {{{"do", "coordinator_open"}, {"study", studyId}},
                         {{"do", "coordinator_export"}, {"out", out.string()}, {"cancel_after", 3}}}}};
  const Run r = runDesktop(dir, script, dir / "t.db");
  INFO(r.err);
  REQUIRE(r.exitCode == 0);
  CHECK(eventsOf(r, "export_progress").size() == 3);
  CHECK(eventsOf(r, "export_done").empty());
  const auto cancelled = eventsOf(r, "export_cancelled");
  REQUIRE(cancelled.size() == 1);
  CHECK(cancelled[0].at("written") == 3);
  CHECK(cancelled[0].at("n") == 10);
  CHECK(cancelled[0].at("removed") == true);
  // The three files written were removed again.
  for (const json& e : eventsOf(r, "export_progress")) CHECK(!fs::exists(out / e.at("file").get<std::string>()));
  std::size_t left = 0;
  if (fs::exists(out))
    for (const auto& entry : fs::directory_iterator(out)) left += entry.is_regular_file();
  CHECK(left == 0);
}

TEST_CASE("FullResolutionCpuField_CancelledFromTheApp_StopsAndIsNotAskedForAgain") {
  if (!at::test::requireXvfb()) return;
  TempDir dir("desktop-field-cancel");
  // The 256³ phantom: its full-resolution field takes the CPU long enough (≈ 1 s on two cores) to
  // be seen running and cancelled; the coarse 1/4 field stays on screen.
  const json script = {{"actions",
                        {{{"do", "select"}, {"structure", "cochlea"}},
                         {{"do", "cancel_field"}},
                         {{"do", "wait"}, {"ms", 1500}},
                         {{"do", "wait_field"}}}}};
  const Run r = runDesktop(dir, script, dir / "t.db", "phantom", (dir / "shot.png").string());
  INFO(r.err);
  REQUIRE(r.exitCode == 0);
  const auto cancelled = eventsOf(r, "field_cancelled");
  REQUIRE(cancelled.size() == 1);
  CHECK(cancelled[0].at("structure") == "cochlea");
  CHECK(cancelled[0].at("downsample") == 1);
  // Cancelled after its last pass (a window of microseconds), the field still arrives: too late to stop.
  const bool inTime = cancelled[0].at("passes_done").get<int>() < cancelled[0].at("passes_planned").get<int>();
  // No full-resolution cochlea field arrives afterwards; the coarse one was there before.
  bool cancelSeen = false, fineAfter = false, coarseBefore = false;
  for (const json& e : r.events) {
    if (e.value("event", "") == "field_cancelled") cancelSeen = true;
    if (e.value("event", "") != "field" || e.value("structure", "") != "cochlea") continue;
    if (!cancelSeen && e.at("downsample").get<int>() > 1) coarseBefore = true;
    if (cancelSeen && e.at("downsample").get<int>() == 1) fineAfter = true;
  }
  CHECK(coarseBefore);
  if (inTime)
    CHECK(!fineAfter);
  else
    MESSAGE("the full-resolution field finished as it was cancelled");
  // Fields computed on the CPU are announced once in the app's messages.
  CHECK(r.err.find("No CUDA GPU: distance fields run on the CPU") != std::string::npos);
}
