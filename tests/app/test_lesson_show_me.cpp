// Answers that teach, in the desktop without a window: after a wrong answer "show me" puts the
// target up in its own WDT view, Back returns to the previous step (an answered question keeps its
// answer and feedback), and a finished lesson lists every question with the answer given, the
// right one, and its picture on request.
#include <doctest/doctest.h>

#include <filesystem>

#include <nlohmann/json.hpp>

#include "headless_desktop.h"
#include "test_support.h"

namespace fs = std::filesystem;
using at::test::TempDir;
using json = nlohmann::json;

namespace {

at::test::HeadlessRun runLessonScript(const json& actions, const fs::path& db, const std::string& user) {
  return at::test::runPanelScript(actions, db, user);
}

}  // namespace

TEST_CASE("after a wrong click, show me highlights the target in its own view, and Back keeps the answer") {
  TempDir dir("desktop-show-me");
  const fs::path db = dir / "tutor.db";
  // inner_ear: four show steps, then "Click the cochlea." in the vestibule's context. The student
  // clicks where the lateral canal lies (wrong), asks to be shown, goes back a step and forward again.
  json actions = {{{"do", "lessons"}, {"course", "temporal_bone"}},
                  {{"do", "lesson"}, {"course", "temporal_bone"}, {"lesson", "inner_ear"}}};
  for (int i = 0; i < 4; ++i) actions.push_back({{"do", "lesson_next"}});
  for (const json& a : json::array({{{"do", "wait_field"}},
                                    {{"do", "click_structure"}, {"structure", "lateral_semicircular_canal"}},
                                    {{"do", "show_me"}},
                                    {{"do", "wait_field"}},
                                    {{"do", "lesson_back"}},
                                    {{"do", "lesson_next"}}}))
    actions.push_back(a);
  const at::test::HeadlessRun r = runLessonScript(actions, db, "learner");
  INFO(r.messages);
  REQUIRE(r.exitCode == 0);
  const auto graded = at::test::eventsOf(r, "graded");
  REQUIRE(graded.size() == 1);
  CHECK_FALSE(graded[0].value("correct", true));
  // Each wait's settle time, and within it when the field alone was on screen.
  const auto settled = at::test::eventsOf(r, "field_settled");
  REQUIRE(settled.size() == 2);
  for (const json& e : settled) {
    INFO(e.dump());
    CHECK(e.at("field_ms").get<double>() >= 0);
    CHECK(e.at("field_ms").get<double>() <= e.at("ms").get<double>());
  }
  const auto shown = at::test::eventsOf(r, "show_me");
  REQUIRE(shown.size() == 1);
  CHECK(shown[0].value("structure", "") == "cochlea");  // the answer, highlighted
  CHECK(shown[0].value("preset", "") == "cochlea_wdt");
  CHECK(shown[0].value("view", "") == "anterior");      // from the side the question asked
  const auto steps = at::test::eventsOf(r, "lesson_step");
  REQUIRE(steps.size() >= 3);
  const json& back = steps[steps.size() - 2];
  CHECK(back.value("position", 0) == 4);
  CHECK(back.value("kind", "") == "show");
  const json& again = steps.back();
  CHECK(again.value("position", 0) == 5);
  CHECK(again.value("answered", false));  // the answer stands: no second try
}

TEST_CASE("a finished lesson reviews each question: the answer given, the right one, and its picture") {
  TempDir dir("desktop-lesson-review");
  const fs::path db = dir / "tutor.db";
  // inner_ear from the start: four show steps, then six questions.
  json actions = {{{"do", "lesson"}, {"course", "temporal_bone"}, {"lesson", "inner_ear"}}};
  for (int i = 0; i < 4; ++i) actions.push_back({{"do", "lesson_next"}});
  // Six questions: locate, identify, name, locate, relation, relation — each answered wrong or by
  // the first choice, then Next.
  for (const json& a : json::array({{{"do", "wait_field"}}, {{"do", "click_structure"}, {"structure", "lateral_semicircular_canal"}},
                                    {{"do", "lesson_next"}}, {{"do", "answer"}, {"value", "vestibule"}},
                                    {{"do", "lesson_next"}}, {{"do", "answer"}, {"value", "horizontal canal"}},
                                    {{"do", "lesson_next"}}, {{"do", "wait_field"}},
                                    {{"do", "click_structure"}, {"structure", "lateral_semicircular_canal"}},
                                    {{"do", "lesson_next"}}, {{"do", "answer"}, {"value", 0}},
                                    {{"do", "lesson_next"}}, {{"do", "answer"}, {"value", 0}},
                                    {{"do", "lesson_next"}},
                                    {{"do", "lesson_review_item"}, {"index", 0}},
                                    {{"do", "lesson_review_item"}, {"index", 2}}}))
    actions.push_back(a);
  const at::test::HeadlessRun r = runLessonScript(actions, db, "reviewer");
  INFO(r.messages);
  REQUIRE(r.exitCode == 0);
  REQUIRE(at::test::eventsOf(r, "lesson_finished").size() == 1);
  const auto items = at::test::eventsOf(r, "review_item");
  REQUIRE(items.size() == 2);
  CHECK(items[0].value("question", "") == "inner_ear.locate_cochlea");
  CHECK_FALSE(items[0].value("correct", true));
  CHECK(items[0].value("structure", "") == "cochlea");  // the picture shows the answer
  CHECK(items[0].value("your_answer", "").rfind("a click on", 0) == 0);
  CHECK(items[0].value("your_answer", "") != "a click on the cochlea");
  CHECK(items[0].value("right_answer", "") == "Cochlea");
  CHECK(items[1].value("question", "") == "inner_ear.name_lateral_canal");
  CHECK(items[1].value("correct", false));  // a catalogue synonym
  CHECK(items[1].value("your_answer", "") == "\"horizontal canal\"");
}
