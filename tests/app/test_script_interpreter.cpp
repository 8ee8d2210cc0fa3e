// The UI-script interpreter without a window: actions drive the model's commands (the ones the
// widgets use) and their events come out in order; a malformed action ends the script with status
// 2, a wait that times out with status 1.
#include <doctest/doctest.h>

#include <algorithm>
#include <set>

#include "headless_desktop.h"
#include "test_support.h"

using namespace at;
using json = nlohmann::json;

using test::eventsOf;

namespace {

test::HeadlessRun run(const test::TempDir& dir, const json& actions, const std::string& dataset = "phantom:64") {
  test::HeadlessOptions options;
  options.dataset = dataset;
  options.db = dir / "t.db";
  options.timeoutSeconds = 300;
  return test::runHeadless({{"actions", actions}}, options);
}


}  // namespace

TEST_CASE("ScriptInterpreter_ViewActions_DriveTheModelAndReportWhatHappened") {
  test::TempDir dir("script-view");
  // Framed on the vestibule from the right and zoomed out, the temporal line lies in the open
  // (the desktop hover test's view).
  const json actions = {{{"do", "select"}, {"structure", "vestibule"}},
                        {{"do", "mode"}, {"value", "bare"}},
                        {{"do", "t"}, {"value", 0.8}},
                        {{"do", "view"}, {"value", "lateral_right"}},
                        {{"do", "zoom"}, {"factor", 0.45}},
                        {{"do", "mode"}, {"value", "wdt"}},
                        {{"do", "wait_field"}},
                        {{"do", "hover_structure"}, {"structure", "temporal_line"}},
                        {{"do", "wait_field"}},
                        {{"do", "clip"}, {"on", true}, {"axis", 2}, {"offset", 1.5}},
                        {{"do", "orbit"}, {"azimuth", 15}},
                        {{"do", "screenshot"}, {"path", "x.png"}}};
  const auto r = run(dir, actions);
  INFO(r.messages);
  REQUIRE(r.exitCode == 0);
  const auto selected = eventsOf(r, "select");
  REQUIRE(selected.size() == 1);
  CHECK(selected[0]["structure"] == "vestibule");
  const auto hs = eventsOf(r, "hover_structure");
  REQUIRE(hs.size() == 1);
  REQUIRE(hs[0]["visible"] == true);
  // Picking on the CPU found the temporal line under its projected centroid.
  const auto hovers = eventsOf(r, "hover");
  REQUIRE(!hovers.empty());
  CHECK(hovers.back()["structure"] == "temporal_line");
  CHECK(hovers.back().contains("highlight_rgb"));
  // wait_field waited for the hovered structure's full-resolution field.
  bool fine = false;
  for (const json& f : eventsOf(r, "field")) fine |= f["structure"] == "temporal_line" && f["downsample"] == 1;
  CHECK(fine);
  CHECK(r.screenshots == std::vector<std::string>{"x.png"});
}

TEST_CASE("ScriptInterpreter_UnknownOrMalformedAction_EndsWithStatus2AndSaysWhich") {
  test::TempDir dir("script-bad");
  auto r = run(dir, {{{"do", "select"}, {"structure", "cochlea"}}, {{"do", "teleport"}}, {{"do", "select"}, {"structure", "stapes"}}});
  CHECK(r.exitCode == 2);
  CHECK(r.messages.find("unknown action \"teleport\"") != std::string::npos);
  CHECK(eventsOf(r, "select").size() == 1);  // what came before ran, nothing after
  r = run(dir, {{{"structure", "cochlea"}}});
  CHECK(r.exitCode == 2);
  CHECK(r.messages.find("\"do\" string") != std::string::npos);
  r = run(dir, {{{"do", "t"}, {"value", "high"}}});
  CHECK(r.exitCode == 2);
  CHECK(r.messages.find("{\"do\":\"t\",\"value\":\"high\"}") != std::string::npos);
  // An argument under the wrong key: the documented one is named as missing, with what the action
  // takes, on one line (not nlohmann's "key 'value' not found").
  r = run(dir, {{{"do", "view"}, {"view", "anterior"}}});
  CHECK(r.exitCode == 2);
  CHECK(r.messages.find("ui script: action {\"do\":\"view\",\"view\":\"anterior\"}: \"value\" missing (view takes value: "
                        "desktop --help view)\n") != std::string::npos);
  CHECK(r.messages.find("json.exception") == std::string::npos);
  r = run(dir, {{{"do", "select"}, {"structure", "spleen"}}});
  CHECK(r.exitCode == 2);
  CHECK(r.messages.find("no structure 'spleen'") != std::string::npos);
  r = run(dir, {{{"do", "mode"}, {"value", "xray"}}});
  CHECK(r.exitCode == 2);
  r = run(dir, {{{"do", "view"}, {"value", "diagonal"}}});
  CHECK(r.exitCode == 2);
  CHECK(r.messages.find("unknown view") != std::string::npos);
  r = run(dir, {{{"do", "study_rate"}, {"item", "x"}, {"rating", 3}}});
  CHECK(r.exitCode == 2);
  CHECK(r.messages.find("needs study_start first") != std::string::npos);
}

TEST_CASE("ScriptInterpreter_WaitThatTimesOut_EndsWithStatus1") {
  test::TempDir dir("script-timeout");
  // Right after a new structure is selected its full-resolution field is not there yet.
  const auto r = run(dir, {{{"do", "select"}, {"structure", "stapes"}}, {{"do", "wait_field"}, {"timeout_ms", 0}}}, "phantom:128");
  CHECK(r.exitCode == 1);
  CHECK(r.messages.find("wait_field timed out") != std::string::npos);
  const auto c = run(dir, {{{"do", "mode"}, {"value", "bare"}}, {{"do", "cancel_field"}, {"timeout_ms", 0}}});
  CHECK(c.exitCode == 1);
  CHECK(c.messages.find("no full-resolution field was computing") != std::string::npos);
}

TEST_CASE("ScriptInterpreter_HoverSweep_RecordsAndReportsEveryVisibleStructure") {
  test::TempDir dir("script-sweep");
  const auto r = run(dir, {{{"do", "view"}, {"value", "lateral_right"}}, {{"do", "hover_sweep"}, {"dwell_ms", 150}}});
  INFO(r.messages);
  REQUIRE(r.exitCode == 0);
  const auto reports = eventsOf(r, "report");
  REQUIRE(reports.size() == 1);
  const json& report = reports[0];
  const auto hovered = eventsOf(r, "hover_structure");
  CHECK(hovered.size() == 16);  // every structure of the phantom, visible or not
  CHECK(report["frames"].get<int>() > 10);
  CHECK(report["window"] == "headless");
  // (How many of the sweep's hovers get their field on screen within the dwell depends on the
  // machine's load; the recorder's highlight count is checked below without timing.)
}

TEST_CASE("ScriptInterpreter_Report_CountsAHighlightOnceTheHoveredFieldIsShown") {
  test::TempDir dir("script-highlight");
  // The view of the ViewActions test, where hovering the temporal line picks it.
  const json actions = {{{"do", "select"}, {"structure", "vestibule"}},
                        {{"do", "view"}, {"value", "lateral_right"}},
                        {{"do", "zoom"}, {"factor", 0.45}},
                        {{"do", "wait_field"}},
                        {{"do", "record"}, {"on", true}},
                        {{"do", "hover_structure"}, {"structure", "temporal_line"}},
                        {{"do", "wait_field"}},
                        {{"do", "report"}}};
  const auto r = run(dir, actions);
  INFO(r.messages);
  REQUIRE(r.exitCode == 0);
  const auto hovers = eventsOf(r, "hover");
  REQUIRE(!hovers.empty());
  REQUIRE(hovers.back()["structure"] == "temporal_line");
  const auto reports = eventsOf(r, "report");
  REQUIRE(reports.size() == 1);
  CHECK(reports[0]["highlights"] == 1);
  CHECK(reports[0]["highlight_ms_max"].get<double>() > 0);
}

TEST_CASE("ScriptInterpreter_ExpertEdits_ChangeTheViewsPresetAndItsFieldParameters") {
  test::TempDir dir("script-expert");
  const auto r = run(dir, {{{"do", "select"}, {"structure", "cochlea"}},
                           {{"do", "tf_add_point"}, {"tf", "data"}, {"x", 500}, {"rgba", {1, 0, 0, 0.5}}},
                           {{"do", "tf_move_point"}, {"tf", "distance"}, {"index", 1}, {"alpha", 0.3}},
                           {{"do", "preset_set"}, {"t", 0.2}, {"rule", "trapezoid"}},
                           {{"do", "preset_save"}, {"name", "My Cochlea!"}, {"export", (dir / "mine.json").string()}},
                           {{"do", "tf_delete_point"}, {"tf", "distance"}, {"index", 99}}});
  CHECK(r.exitCode == 2);  // the last one: no point 99
  const auto expert = eventsOf(r, "expert");
  REQUIRE(expert.size() == 1);
  CHECK(eventsOf(r, "tf_point").size() == 2);
  const auto saved = eventsOf(r, "preset_saved");
  REQUIRE(saved.size() == 1);
  CHECK(saved[0]["id"] == "my_cochlea");
  auto preset = render::loadPreset(dir / "mine.json");
  REQUIRE(preset);
  CHECK(preset->t == doctest::Approx(0.2));
  CHECK(preset->weightRule == "trapezoid");
  CHECK(preset->dataTf.size() == expert[0]["preset"]["data_tf"].size() + 1);
}
