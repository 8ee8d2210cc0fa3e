// A locate question is asked on a neighbouring region's view (lessons::sceneFor: the target is not
// marked). The view must still hold the whole target: "Click the cochlea" framed on the vestibule
// alone left half of the cochlea outside the window.
#include <doctest/doctest.h>

#include <optional>

#include "headless_desktop.h"

using namespace at;
using json = nlohmann::json;

TEST_CASE("LessonLocateQuestion_ViewOfTheRegion_HoldsTheWholeTarget") {
  test::TempDir dir("at-framing");
  test::HeadlessOptions options;
  options.dataset = "phantom";
  options.db = dir / "f.db";
  options.width = 1280;
  options.height = 720;
  std::optional<render::Camera> camera;
  std::vector<Vec3> cochlea, vestibule;
  std::uint16_t vestibuleLabel = 0;
  int viewW = 0, viewH = 0;
  std::uint16_t shown = 0;
  options.drawPanels = [&](app::DesktopModel& model) {
    camera = model.explore().camera();
    shown = model.explore().shownLabel();
    viewW = model.layout().viewPixelsW();
    viewH = model.layout().viewPixelsH();
    if (cochlea.empty()) {
      const Structure* c = model.dataset().findStructure("cochlea");
      const Structure* v = model.dataset().findStructure("vestibule");
      REQUIRE(c);
      REQUIRE(v);
      cochlea = model.explore().frameOf(c->label)->pointsMm;
      vestibule = model.explore().frameOf(v->label)->pointsMm;
      vestibuleLabel = v->label;
    }
  };
  const json script = {{"actions", json::array({
      {{"do", "lessons"}, {"course", "temporal_bone"}},
      {{"do", "lesson"}, {"course", "temporal_bone"}, {"lesson", "inner_ear"}},
      {{"do", "lesson_next"}}, {{"do", "lesson_next"}}, {{"do", "lesson_next"}}, {{"do", "lesson_next"}},
      {{"do", "wait_field"}},
  })}};
  auto run = test::runHeadless(script, options);
  INFO(run.messages);
  REQUIRE(run.exitCode == 0);
  const auto steps = test::eventsOf(run, "lesson_step");
  REQUIRE_FALSE(steps.empty());
  REQUIRE(steps.back().value("question", "") == "inner_ear.locate_cochlea");
  REQUIRE(camera);
  CHECK(shown == vestibuleLabel);  // the question's region, as the course asks
  REQUIRE_FALSE(cochlea.empty());
  auto outside = [&](const std::vector<Vec3>& points) {
    int n = 0;
    for (const Vec3& p : points) {
      const auto px = camera->project(p, viewW, viewH);
      n += !px || (*px)[0] < 0 || (*px)[1] < 0 || (*px)[0] >= viewW || (*px)[1] >= viewH;
    }
    return n;
  };
  CHECK(outside(cochlea) == 0);    // the target, all of it
  CHECK(outside(vestibule) == 0);  // and the region the question is asked in
}
