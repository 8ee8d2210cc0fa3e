// Choosing a structure in the desktop brings it into view: the structure list (and the UI script's
// `select`) frames a structure the view does not show whole (or shows small) from the side the view
// looks from; a click on a structure in the 3-D view keeps the camera where the user put it. On the
// abdominal CT the start view framed the spleen, and the liver chosen from the list lay mostly off
// screen.
#include <doctest/doctest.h>

#include <optional>
#include <vector>

#include "headless_desktop.h"

using namespace at;
using json = nlohmann::json;

namespace {

// The camera and view size each frame ends with, and which structure was selected.
struct FrameSeen {
  render::Camera camera;
  int width = 0, height = 0;
  std::uint16_t selected = 0;
};

}  // namespace

TEST_CASE("DesktopSelect_FromTheList_FramesEveryStructureTheViewDoesNotShowWhole_AClickInTheViewKeepsTheCamera") {
  test::TempDir dir("at-select-framing");
  test::HeadlessOptions options;
  options.dataset = "phantom:128";
  options.db = dir / "s.db";
  options.width = 1280;
  options.height = 720;
  std::vector<FrameSeen> frames;
  std::vector<std::string> ids;
  // Copies: the model (and the frames it holds) is gone when runHeadless returns.
  std::map<std::uint16_t, render::StructureFrame> frameOf;
  options.drawPanels = [&](app::DesktopModel& model) {
    frames.push_back({model.explore().camera(), model.layout().viewPixelsW(), model.layout().viewPixelsH(),
                      model.explore().selected()});
    if (frameOf.empty())
      for (const Structure& s : model.dataset().structures)
        if (const render::StructureFrame* frame = model.explore().frameOf(s.label)) frameOf[s.label] = *frame;
  };
  // Every structure from the list, each after zooming in on the one before (the view framed on it,
  // then closer, as a user looks at it).
  json actions = json::array();
  for (const Structure& s : test::phantomOfSize(128).structures) {
    ids.push_back(s.id);
    actions.push_back({{"do", "zoom"}, {"factor", 4}});
    actions.push_back({{"do", "select"}, {"structure", s.id}});
    actions.push_back({{"do", "wait"}, {"ms", 30}});
  }
  // Then a click in the view on a structure shown zoomed in: the camera stays.
  actions.push_back({{"do", "select"}, {"structure", "vestibule"}});
  actions.push_back({{"do", "wait"}, {"ms", 30}});
  actions.push_back({{"do", "zoom"}, {"factor", 6}});
  actions.push_back({{"do", "wait"}, {"ms", 30}});
  actions.push_back({{"do", "click"}, {"view_at", {0.5, 0.5}}});
  actions.push_back({{"do", "wait"}, {"ms", 30}});
  auto run = test::runHeadless({{"actions", actions}}, options);
  INFO(run.messages);
  REQUIRE(run.exitCode == 0);
  REQUIRE_FALSE(frames.empty());

  // After each list selection, the first frame with it selected shows it whole (a wait follows each
  // selection before the next zoom).
  const auto selects = test::eventsOf(run, "select");
  REQUIRE(selects.size() >= ids.size() + 1);
  std::size_t framedCount = test::eventsOf(run, "framed").size();
  MESSAGE(framedCount << " of " << ids.size() << " structures framed when chosen from the list");
  CHECK(framedCount > 0);
  // The list's selections in order (then the vestibule's); the click's comes after them.
  std::vector<std::uint16_t> listed;
  for (const std::string& id : ids) listed.push_back(test::phantomOfSize(128).findStructure(id)->label);
  std::size_t checked = 0, next = 0;
  for (std::size_t i = 1; i < frames.size() && next < listed.size(); ++i) {
    const FrameSeen& f = frames[i];
    if (f.selected == frames[i - 1].selected) continue;
    while (next < listed.size() && listed[next] != f.selected) ++next;  // one selection may fall before a frame
    if (next == listed.size()) break;
    CAPTURE(f.selected);
    REQUIRE(frameOf.count(f.selected) == 1);
    CHECK(render::shareInView(frameOf.at(f.selected), f.camera, f.width, f.height) >= app::ExploreState::kShownWhole);
    ++checked;
    ++next;
  }
  CHECK(checked + 2 >= ids.size());  // every change of selection (one may fall before the first frame)

  // The click: whatever it selects, the zoomed camera stays.
  const auto last = selects.back();
  CHECK(last.value("structure", "") != "");
  REQUIRE(frames.size() >= 3);
  CHECK(frames.back().camera == frames[frames.size() - 2].camera);
}
