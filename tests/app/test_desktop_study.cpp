// The desktop app's study screens as a participant and a coordinator use them: scripted runs under
// Xvfb (Mesa) of the shipped study on the phantom. The participant screens' drawn labels (printed
// by the app as "study_screen" events) must not name a structure, preset, condition or the study.
#include <doctest/doctest.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <optional>
#include <string>
#include <sys/wait.h>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/strings.h"
#include "quiz/study_report.h"
#include "desktop_script.h"
#include "headless_desktop.h"
#include "test_support.h"
#include "volume/png_image.h"

namespace fs = std::filesystem;
using at::test::TempDir;
using json = nlohmann::json;

namespace {

using Run = at::test::DesktopRun;
using at::test::eventsOf;

Run runStudyScript(const TempDir& dir, const json& script, const fs::path& db, const std::string& screenshot) {
  at::test::DesktopOptions options;
  options.size = "800x600";
  options.db = db;
  options.screenshot = screenshot;
  return at::test::runDesktopScript(dir, script, options);
}

json shippedStudy() {
  std::ifstream in(at::test::sourceDir() / "data" / "studies" / "paper_survey.json");
  return json::parse(in);
}

// Everything that would unblind a participant: structure ids (also with spaces), preset ids,
// condition ids and labels, the study's id and title.
std::vector<std::string> forbiddenWords(const json& study) {
  std::vector<std::string> words = {study["id"].get<std::string>(), study["title"].get<std::string>()};
  for (const json& s : study["structures"]) {
    std::string id = s.get<std::string>(), spaced = id;
    std::replace(spaced.begin(), spaced.end(), '_', ' ');
    words.insert(words.end(), {id, spaced});
    for (const json& c : study["conditions"]) words.push_back(id + c["preset_suffix"].get<std::string>());
  }
  for (const json& c : study["conditions"]) words.insert(words.end(), {c["id"].get<std::string>(), c["label"].get<std::string>()});
  return words;
}

json rateAll(const json& study, int rating) {
  json actions = json::array();
  for (const json& item : study["items"]) actions.push_back({{"do", "study_rate"}, {"item", item["id"]}, {"rating", rating}});
  return actions;
}

void append(json& list, const json& more) {
  for (const json& a : more) list.push_back(a);
}

}  // namespace

TEST_CASE("the study runner shows no structure names and its ratings land in the database") {
  if (!at::test::requireXvfb()) return;
  TempDir dir("at-study-ui");
  const json study = shippedStudy();
  const std::string studyId = study["id"];
  json actions = json::array();
  actions.push_back({{"do", "study_start"}, {"study", studyId}, {"participant", "P1"}, {"group", "medical"}});
  actions.push_back({{"do", "wait"}, {"ms", 100}});
  actions.push_back({{"do", "wait_field"}});
  actions.push_back({{"do", "screenshot"}, {"path", (dir / "view_a.png").string()}});
  actions.push_back({{"do", "study_toggle"}});
  actions.push_back({{"do", "wait_field"}});
  actions.push_back({{"do", "screenshot"}, {"path", (dir / "view_b.png").string()}});
  append(actions, rateAll(study, 2));
  actions.push_back({{"do", "study_comment"}, {"text", "first"}});
  actions.push_back({{"do", "study_next"}});
  actions.push_back({{"do", "wait"}, {"ms", 100}});
  actions.push_back({{"do", "study_toggle"}, {"side", "B"}});
  actions.push_back({{"do", "study_toggle"}, {"side", "A"}});
  append(actions, rateAll(study, 4));
  actions.push_back({{"do", "study_next"}});
  actions.push_back({{"do", "wait"}, {"ms", 100}});
  const fs::path db = dir / "study.db", shot = dir / "participant.png";
  const Run r = runStudyScript(dir, {{"actions", actions}}, db, shot.string());
  INFO("stderr: " << r.err);
  REQUIRE(r.exitCode == 0);

  // Three participant screens were shown (structures 1, 2, 3), each only in the participant window.
  const auto screens = eventsOf(r, "study_screen");
  REQUIRE(screens.size() >= 3);
  const std::vector<std::string> forbidden = forbiddenWords(study);
  const std::size_t n = study["structures"].size();
  for (std::size_t k = 0; k < 3; ++k) {
    const json& screen = screens[k];
    CHECK(screen["windows"] == json::array({"Preference study"}));
    std::string all;
    for (const json& label : screen["labels"]) all += at::str::lower(label.get<std::string>()) + "\n";
    INFO("screen " << k << ": " << all);
    CHECK(all.find("structure " + std::to_string(k + 1) + " of " + std::to_string(n)) != std::string::npos);
    CHECK(all.find(at::str::lower(study["items"][0]["wording"].get<std::string>())) != std::string::npos);
    CHECK(all.find(at::str::lower(study["scale"]["anchors"]["1"].get<std::string>())) != std::string::npos);
    for (const std::string& word : forbidden) CHECK_MESSAGE(all.find(at::str::lower(word)) == std::string::npos, word);
  }

  const auto recorded = eventsOf(r, "study_recorded");
  REQUIRE(recorded.size() == 2);
  CHECK(recorded[0]["toggles"] == 1);
  CHECK(recorded[1]["toggles"] == 2);
  CHECK(recorded[0]["view_ms_a"].get<double>() > 0);
  CHECK(recorded[0]["view_ms_b"].get<double>() > 0);

  // The ratings are in the database: 2 structures × items, read back by the terminal commands.
  const std::size_t items = study["items"].size();
  const auto status = at::test::runApp("study status " + studyId + " --db '" + db.string() + "'");
  INFO(status.out << status.err);
  CHECK(status.exitCode == 0);
  CHECK(status.out.find("P1") != std::string::npos);
  CHECK(status.out.find(std::to_string(2 * items) + "/" + std::to_string(n * items) + " ratings") != std::string::npos);

  // Each rating records the quality the participant saw: the full level (ratings wait for it) and
  // the time it took to get there; the export carries them.
  const auto exported = at::test::runApp("study export " + studyId + " --out '" + (dir / "export").string() + "' --db '" +
                                         db.string() + "'");
  INFO(exported.out << exported.err);
  REQUIRE(exported.exitCode == 0);
  std::ifstream longCsv(dir / "export" / "responses_long.csv");
  std::stringstream csvText;
  csvText << longCsv.rdbuf();
  const auto rows = at::quiz::parseCsv(csvText.str());
  REQUIRE(rows.size() == 1 + 2 * items);
  const auto col = [&](const std::string& name) {
    const auto it = std::find(rows[0].begin(), rows[0].end(), name);
    REQUIRE(it != rows[0].end());
    return std::size_t(it - rows[0].begin());
  };
  for (std::size_t i = 1; i < rows.size(); ++i) {
    CHECK(rows[i][col("quality_full_level")] == "5");
    CHECK(rows[i][col("quality_level")] == rows[i][col("quality_full_level")]);
    CHECK_FALSE(rows[i][col("settle_ms")].empty());
    CHECK_FALSE(rows[i][col("quality_scale")].empty());
  }

  // The screenshot shows the volume view beside the participant panel (not an empty view).
  auto image = at::readPng(shot.string());
  REQUIRE(image);
  int lit = 0, total = 0;
  for (int y = 0; y < image->height; y += 4)
    for (int x = image->width / 2; x < image->width; x += 4) {
      const std::uint8_t* p = image->pixel(x, y);
      lit += (p[0] + p[1] + p[2] > 60) ? 1 : 0;
      ++total;
    }
  CHECK(lit > total / 100);

  // Toggling A/B changes what the volume view shows (the two conditions' presets differ).
  auto a = at::readPng((dir / "view_a.png").string()), b = at::readPng((dir / "view_b.png").string());
  REQUIRE(a);
  REQUIRE(b);
  REQUIRE(a->width == b->width);
  double diff = 0;
  int samples = 0;
  for (int y = 0; y < a->height; y += 2)
    for (int x = a->width / 2; x < a->width; x += 2) {
      for (int c = 0; c < 3; ++c) diff += std::abs(int(a->pixel(x, y)[c]) - int(b->pixel(x, y)[c]));
      ++samples;
    }
  CHECK(diff / samples > 3.0);
}

// The participant screen each study_next opens is shown before the script goes on, however slow
// the frames: a stand-in for the participant window draws a new screen one frame and announces it
// the next, as the panel does, with each frame slower than the script's waits.
TEST_CASE("every participant screen is on display before the script acts on the next one") {
  TempDir dir("at-study-ui");
  const json study = shippedStudy();
  json actions = json::array();
  actions.push_back({{"do", "study_start"}, {"study", study["id"]}, {"participant", "P3"}, {"group", "medical"}});
  for (int k = 0; k < 2; ++k) {
    append(actions, rateAll(study, 3));
    actions.push_back({{"do", "study_next"}});
    actions.push_back({{"do", "wait"}, {"ms", 20}});
    actions.push_back({{"do", "study_toggle"}});
  }
  actions.push_back({{"do", "study_close"}});
  std::optional<int> drawn;  // the position drawn last frame, to announce (0: the closing screen)
  at::test::HeadlessOptions options;
  options.db = dir / "study.db";
  options.dataset = "phantom:64";
  options.drawPanels = [&](at::app::DesktopModel& model) {
    at::app::StudyController& s = model.study();
    if (!s.participantActive()) return;
    if (s.takeNewScreen()) {
      const auto& p = *s.participant();
      drawn = p.trial ? int(p.participant.trials[*p.trial].position) + 1 : 0;
    } else if (drawn) {
      s.announce({{"event", "study_screen"}, {"position", *std::exchange(drawn, std::nullopt)}});
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(40));  // a frame slower than the waits
  };
  const at::test::HeadlessRun r = at::test::runHeadless({{"actions", actions}}, options);
  INFO("messages: " << r.messages);
  REQUIRE(r.exitCode == 0);
  // In order: screen 1, recorded 1, screen 2, toggle, recorded 2, screen 3, toggle.
  std::vector<std::string> seen;
  for (const json& e : r.events) {
    const std::string kind = e.value("event", "");
    if (kind == "study_screen") seen.push_back("screen " + std::to_string(e["position"].get<int>()));
    if (kind == "study_recorded") seen.push_back("recorded " + std::to_string(e["position"].get<int>()));
    if (kind == "study_toggle") seen.push_back("toggle");
  }
  CHECK(seen == std::vector<std::string>{"screen 1", "recorded 1", "screen 2", "toggle", "recorded 2", "screen 3", "toggle"});
}

// Without a window: the coordinator's export and summary are the app's logic (at_app_core).
TEST_CASE("the coordinator export writes the ten study files and shows the summary") {
  TempDir dir("at-study-ui");
  const json study = shippedStudy();
  const std::string studyId = study["id"];
  json actions = json::array();
  actions.push_back({{"do", "study_start"}, {"study", studyId}, {"participant", "P2"}, {"group", "non-medical"}});
  append(actions, rateAll(study, 1));
  actions.push_back({{"do", "study_next"}});
  actions.push_back({{"do", "study_close"}});
  actions.push_back({{"do", "coordinator_open"}, {"study", studyId}});
  actions.push_back({{"do", "coordinator_export"}, {"out", (dir / "export").string()}});
  actions.push_back({{"do", "coordinator_summary"}});
  at::test::HeadlessOptions options;
  options.db = dir / "study.db";
  const at::test::HeadlessRun r = at::test::runHeadless({{"actions", actions}}, options);
  INFO("messages: " << r.messages);
  REQUIRE(r.exitCode == 0);

  const auto progress = at::test::eventsOf(r, "export_progress");
  REQUIRE(progress.size() == 10);
  for (std::size_t k = 0; k < progress.size(); ++k) {
    CHECK(progress[k]["k"] == k + 1);
    CHECK(progress[k]["n"] == 10);
    const fs::path file = dir / "export" / progress[k]["file"].get<std::string>();
    CHECK_MESSAGE(fs::is_regular_file(file), file.string());
    CHECK(fs::file_size(file) > 0);
  }
  // One structure rated: the long table has a header and one row per item.
  const std::string longCsv = at::test::readFile(dir / "export" / "responses_long.csv");
  const std::size_t items = study["items"].size();
  CHECK(std::count(longCsv.begin(), longCsv.end(), '\n') == std::ptrdiff_t(items + 1));

  const auto summary = at::test::eventsOf(r, "study_summary");
  REQUIRE(summary.size() == 1);
  bool sawAll = false;
  for (const json& cell : summary[0]["cells"]) {
    if (cell["group"] != "all") continue;
    sawAll = true;
    CHECK(cell["n"] == 1);
    // Rated 1 (prefer A) on the shown scale: unblinded it is 1 or 5 depending on which side was WDT.
    const double mean = cell["mean"];
    CHECK((mean == doctest::Approx(1) || mean == doctest::Approx(5)));
  }
  CHECK(sawAll);
  REQUIRE(summary[0]["completion"].size() == 1);
  CHECK(summary[0]["completion"][0]["participant"] == "P2");
  CHECK(summary[0]["completion"][0]["given"] == items);
}

// Ratings wait for the full quality level of the side on screen, and each records the
// level, the full level's resolution and the settle time. A stand-in view reports a coarse image
// for the first frames of each side, then the full level; headless, without a window.
TEST_CASE("study ratings wait for the full quality level and record it with each rating") {
  TempDir dir("at-study-ui");
  const json study = shippedStudy();
  const std::string studyId = study["id"];
  json actions = json::array();
  actions.push_back({{"do", "study_start"}, {"study", studyId}, {"participant", "P4"}, {"group", "medical"}});
  append(actions, rateAll(study, 2));
  actions.push_back({{"do", "study_next"}});
  actions.push_back({{"do", "study_toggle"}, {"side", "B"}});
  append(actions, rateAll(study, 4));
  actions.push_back({{"do", "study_next"}});
  actions.push_back({{"do", "study_close"}});
  actions.push_back({{"do", "coordinator_open"}, {"study", studyId}});
  actions.push_back({{"do", "coordinator_export"}, {"out", (dir / "export").string()}});

  constexpr int kCoarseFrames = 4;
  int coarseLeft = kCoarseFrames;
  std::string shownKey;
  int refusedWhileCoarse = 0, acceptedWhileCoarse = 0, wrongImageReady = 0;
  at::test::HeadlessOptions options;
  options.db = dir / "study.db";
  options.dataset = "phantom:64";
  bool toAnnounce = false;
  options.drawPanels = [&](at::app::DesktopModel& model) {
    at::app::StudyController& s = model.study();
    if (!s.participantActive()) return;
    if (s.takeNewScreen()) {  // drawn this frame, announced the next (as the panel does)
      toAnnounce = true;
    } else if (std::exchange(toAnnounce, false)) {
      s.announce({{"event", "study_screen"}});
    }
    if (!s.participant()->trial) return;
    const auto shown = s.shown();
    REQUIRE(shown);
    const std::string key = shown->structure + "/" + shown->preset.id.value_or("");
    if (key != shownKey) {  // a new trial or side: its image starts coarse
      shownKey = key;
      coarseLeft = kCoarseFrames;
    }
    at::app::StudyController::ViewQuality q;
    q.structure = shown->structure;
    q.presetId = shown->preset.id.value_or("");
    q.mode = shown->preset.mode;
    q.fullLevel = 5;
    q.scale = 0.5;
    if (coarseLeft > 0) {
      // An image of another preset at full quality does not count for this side.
      at::app::StudyController::ViewQuality other = q;
      other.presetId += "_other";
      other.level = 5;
      s.noteViewQuality(other);
      wrongImageReady += s.readyToRate();
      --coarseLeft;
      q.level = 0;
      s.noteViewQuality(q);
      const std::string item = study["items"][0]["id"];
      auto st = s.rate(item, 3);
      (st ? acceptedWhileCoarse : refusedWhileCoarse) += 1;
      if (!st) CHECK((st.error().kind == at::ErrorKind::Unavailable));
    } else {
      q.level = 5;
      q.settledMs = 1234.0;
      s.noteViewQuality(q);
    }
  };
  const at::test::HeadlessRun r = at::test::runHeadless({{"actions", actions}}, options);
  INFO("messages: " << r.messages);
  REQUIRE(r.exitCode == 0);
  CHECK(acceptedWhileCoarse == 0);
  CHECK(wrongImageReady == 0);
  CHECK(refusedWhileCoarse >= 2 * kCoarseFrames);  // two trials' first side (the second also after its toggle)

  const auto rows = at::quiz::parseCsv(at::test::readFile(dir / "export" / "responses_long.csv"));
  const std::size_t items = study["items"].size();
  REQUIRE(rows.size() == 1 + 2 * items);
  const auto col = [&](const std::string& name) {
    const auto it = std::find(rows[0].begin(), rows[0].end(), name);
    REQUIRE(it != rows[0].end());
    return std::size_t(it - rows[0].begin());
  };
  for (std::size_t i = 1; i < rows.size(); ++i) {
    CHECK(rows[i][col("quality_level")] == "5");
    CHECK(rows[i][col("quality_full_level")] == "5");
    CHECK(rows[i][col("quality_scale")] == "0.5");
    CHECK(rows[i][col("settle_ms")] == "1234");
  }
}
