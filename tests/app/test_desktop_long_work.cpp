// Long work and failures in the desktop, without a window (the logic is at_app_core's):
// importing from the app with progress and cancel, a file that does not load, cancelling a study
// export part way, and cancelling a full-resolution CPU field. Each run has its own database.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "headless_desktop.h"
#include "cli_checks.h"
#include "test_support.h"

namespace fs = std::filesystem;
using at::test::TempDir;
using json = nlohmann::json;

namespace {

using Run = at::test::HeadlessRun;
using at::test::eventsOf;


Run runDesktop(const TempDir&, const json& script, const fs::path& db, const std::string& dataset = "phantom:128") {
  at::test::HeadlessOptions options;
  options.dataset = dataset;
  options.db = db;
  return at::test::runHeadless(script, options);
}

bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

}  // namespace

TEST_CASE("ImportInTheApp_FileThatDoesNotLoad_ShowsTheLoadersMessageStoresNothingAndTheAppKeepsWorking") {
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
  const Run r = runDesktop(dir, script, db, "phantom:128");
  INFO(r.messages);
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
  CHECK(r.messages.find("import: " + message) != std::string::npos);
  CHECK(eventsOf(r, "import_done").empty());
  CHECK(!eventsOf(r, "field").empty());
  CHECK(at::test::importedDatasetNames(db).empty());

  // A scripted cancel_at must name a stage.
  const Run bad = runDesktop(dir, {{"actions", {{{"do", "import"}, {"volume", broken.string()}, {"name", "x"}, {"cancel_at", "later"}}}}},
                             db);
  CHECK(bad.exitCode == 2);
  CHECK(bad.messages.find("cancel_at") != std::string::npos);
}

TEST_CASE("ImportInTheApp_Cancelled_StoresNothingAndTheNameStaysFree") {
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
  INFO(r.messages);
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
  CHECK(at::test::importedDatasetNames(db) == std::vector<std::string>{"abdomen"});
}

TEST_CASE("StudyExport_CancelledPartWay_StopsAndLeavesNoPartialSetBehind") {
  TempDir dir("desktop-export-cancel");
  std::ifstream in(at::test::sourceDir() / "data" / "studies" / "paper_survey.json");
  const std::string studyId = json::parse(in).at("id");
  const fs::path out = dir / "export";
  const json script = {{"actions",
                        {{{"do", "coordinator_open"}, {"study", studyId}},
                         {{"do", "coordinator_export"}, {"out", out.string()}, {"cancel_after", 3}}}}};
  const Run r = runDesktop(dir, script, dir / "t.db");
  INFO(r.messages);
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
  TempDir dir("desktop-field-cancel");
  // The 256³ phantom: its full-resolution field takes the CPU long enough (≈ 1 s on two cores) to
  // be seen running and cancelled; the coarse 1/4 field stays on screen.
  const json script = {{"actions",
                        {{{"do", "select"}, {"structure", "cochlea"}},
                         {{"do", "cancel_field"}},
                         {{"do", "wait"}, {"ms", 1500}},
                         {{"do", "wait_field"}}}}};
  const Run r = runDesktop(dir, script, dir / "t.db", "phantom");
  INFO(r.messages);
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
  CHECK(r.messages.find("No CUDA GPU: distance fields run on the CPU") != std::string::npos);
}

// An instructor's head CT stored without its rescale (headsq): imported from the app as it is, the
// app says its values are plain intensities and how to read them in HU; imported with the intercept
// the form offers, it is CT in HU, and the dataset keeps that reading for every later open.
TEST_CASE("ImportInTheApp_CtStoredWithoutItsRescale_SaysHowToReadItAndKeepsTheInterceptGiven") {
  if (!at::test::requireSharedData("desktop import rescale")) return;
  TempDir dir("desktop-import-rescale");
  const fs::path db = dir / "t.db";
  const std::string head = at::test::sharedData("headsq/dicom").string();
  const json script = {{"actions",
                        {{{"do", "import"}, {"volume", head}, {"name", "head_as_stored"}},
                         {{"do", "import"}, {"volume", head}, {"name", "head_bad"}, {"intercept", -1024}, {"slope", 0}},
                         {{"do", "import"}, {"volume", head}, {"name", "head"}, {"intercept", -1024}},
                         {{"do", "open_imported"}}}}};
  const Run r = runDesktop(dir, script, db);
  INFO(r.messages);
  REQUIRE(r.exitCode == 0);
  const auto done = eventsOf(r, "import_done");
  REQUIRE(done.size() == 2);
  CHECK(done[0].at("values") == "plain");
  CHECK(done[1].at("values") == "hu");
  CHECK(done[0].at("values_reason").get<std::string>().find("--intercept -1024 reads it in HU") != std::string::npos);
  CHECK(done[1].at("values_reason").get<std::string>().find("reads it in HU") == std::string::npos);
  const auto failed = eventsOf(r, "import_failed");
  REQUIRE(failed.size() == 1);
  CHECK(at::test::importedDatasetNames(db) == std::vector<std::string>{"head", "head_as_stored"});
  // Later opens read "head" in HU: the slice command's grey window is the CT one.
  const auto slice = at::test::runApp("slice head --db '" + db.string() + "' --axis z --index 40 --out '" +
                                      (dir / "s.png").string() + "'");
  REQUIRE_MESSAGE(slice.exitCode == 0, slice.err);
  CHECK(slice.out.find("window 400,2000") != std::string::npos);
}
