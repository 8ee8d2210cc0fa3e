// The desktop app at 1280×720 (a laptop screen) under Xvfb: after an order and a relation question
// of the temporal-bone course are answered, the feedback and the Next button are inside the window
// and inside the part of the Lessons panel that can be seen, without the student scrolling. The
// rectangles come from the frame the app drew ("widgets" action); the screenshots are kept in the
// test's folder for a person to look at.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "desktop_exam_fixtures.h"
#include "desktop_script.h"
#include "test_support.h"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// `inner` lies inside `outer` ([x0, y0, x1, y1], a pixel of slack for rounding).
bool inside(const json& inner, const json& outer) {
  return inner[0].get<double>() >= outer[0].get<double>() - 1 && inner[1].get<double>() >= outer[1].get<double>() - 1 &&
         inner[2].get<double>() <= outer[2].get<double>() + 1 && inner[3].get<double>() <= outer[3].get<double>() + 1;
}

}  // namespace

TEST_CASE("at 1280x720 the order and relation feedback and the Next button are in view without scrolling") {
  if (!at::test::requireXvfb()) return;
  at::test::TempDir dir("desktop-fold");
  const fs::path db = dir / "tutor.db";
  at::test::prepareStudent(db);  // mastoidectomy_landmarks needs facial_nerve and middle_ear
  // mastoidectomy_landmarks: four show steps, two locate, identify, name, order, relation.
  json actions = {{{"do", "lesson"}, {"course", "temporal_bone"}, {"lesson", "mastoidectomy_landmarks"}}};
  for (int i = 0; i < 4; ++i) actions.push_back({{"do", "lesson_next"}});
  for (const json& a : json::array(
           {{{"do", "wait_field"}}, {{"do", "click_structure"}, {"structure", "temporal_line"}}, {{"do", "lesson_next"}},
            {{"do", "wait_field"}}, {{"do", "click_structure"}, {"structure", "sigmoid_sinus"}}, {{"do", "lesson_next"}},
            {{"do", "answer"}, {"value", 0}}, {{"do", "lesson_next"}},
            {{"do", "answer"}, {"value", "lateral canal"}}, {{"do", "lesson_next"}},
            // The order question answered backwards: the longest feedback, the right order spelled out.
            {{"do", "answer"}, {"value", {"lateral_semicircular_canal", "mastoid_air_cells"}}},
            {{"do", "widgets"}}, {{"do", "screenshot"}, {"path", (dir / "order.png").string()}},
            {{"do", "lesson_next"}}, {{"do", "answer"}, {"value", 0}},
            {{"do", "widgets"}}, {{"do", "screenshot"}, {"path", (dir / "relation.png").string()}}}))
    actions.push_back(a);
  const at::test::DesktopRun r = at::test::runLaptopScript(dir, actions, db, "examinee");
  INFO(r.err);
  REQUIRE(r.exitCode == 0);
  const auto graded = at::test::eventsOf(r.events, "graded");
  REQUIRE(graded.size() == 6);
  const auto frames = at::test::eventsOf(r.events, "widgets");
  REQUIRE(frames.size() == 2);
  const json window = {0, 0, at::test::kLaptopWidth, at::test::kLaptopHeight};
  for (const json& frame : frames) {
    INFO(frame.dump());
    CHECK(frame.value("window", "") == std::to_string(at::test::kLaptopWidth) + "x" + std::to_string(at::test::kLaptopHeight));
    for (const char* name : {"lesson_feedback", "lesson_next"}) {
      INFO(name);
      REQUIRE(frame["widgets"].contains(name));
      const json& w = frame["widgets"][name];
      CHECK(inside(w["rect"], w["clip"]));  // not scrolled out of its panel
      CHECK(inside(w["rect"], window));     // not below the window's edge
    }
  }
  CHECK(fs::file_size(dir / "order.png") > 0);
  CHECK(fs::file_size(dir / "relation.png") > 0);
}
