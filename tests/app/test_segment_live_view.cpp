// The segment editor's edits reach the 3-D view in the same session: an unlabelled scan shown
// whole turns into the structure view when the first label is painted (the structure selected,
// pickable under the cursor, its distance field computed), undo takes it away again (the whole
// volume), redo brings it back. Headless (the model's picking on the CPU) and under Xvfb (the
// window's pixels at the painted place in the structure's highlight colour).
#include <doctest/doctest.h>

#include <cmath>

#include "box_volume.h"
#include "desktop_script.h"
#include "headless_desktop.h"
#include "test_support.h"
#include "volume/png_image.h"

using namespace at;
using nlohmann::json;
namespace fs = std::filesystem;

TEST_CASE("desktop model: a label painted on an unlabelled scan is shown, picked and fielded at once; undo and redo follow") {
  test::TempDir dir;
  const fs::path box = test::writeBox(dir);
  const int cx = 320 + (800 - 320) / 2, cy = 240;  // the view's centre (no docked editor at 800 × 480)
  const json wait = {{"do", "wait"}, {"ms", 30}};  // a frame: the edit reaches the view at its start
  const json actions = json::array({
      {{"do", "view"}, {"value", "anterior"}},
      {{"do", "hover"}, {"x", cx}, {"y", cy}},  // the whole volume: nothing to pick
      {{"do", "segment_open"}},
      {{"do", "segment_label"}, {"name", "patch"}},
      wait,
      {{"do", "segment_tool"}, {"tool", "paint"}, {"brush_mm", 3.0}},
      {{"do", "click"}, {"x", cx}, {"y", cy}},
      wait,
      {{"do", "segment_tool"}, {"tool", "seeds"}},  // clicks select again
      {{"do", "hover"}, {"x", cx}, {"y", cy}},
      {{"do", "wait_field"}, {"timeout_ms", 60000}},
      {{"do", "segment_undo"}},
      wait,
      {{"do", "segment_redo"}},
      wait,
      {{"do", "hover"}, {"x", cx + 1}, {"y", cy}},
  });
  test::HeadlessOptions options;
  options.dataset = box.string();
  options.db = dir / "t.db";
  const auto run = test::runHeadless({{"actions", actions}}, options);
  CAPTURE(run.messages);
  REQUIRE(run.exitCode == 0);

  const auto shown = test::eventsOf(run, "labels_shown");
  REQUIRE(shown.size() == 4);  // the label added (no voxels yet), painted, undone, redone
  CHECK(shown[0]["whole_volume"] == true);
  CHECK(shown[1]["whole_volume"] == false);
  CHECK(shown[1]["selected"] == "patch");
  CHECK(shown[1].contains("box"));
  CHECK(shown[2]["whole_volume"] == true);  // undone: the scan is unlabelled again
  CHECK(shown[2]["selected"] == "");
  CHECK(shown[3]["whole_volume"] == false);
  CHECK(shown[3]["selected"] == "patch");
  CHECK(shown[3]["box"] == shown[1]["box"]);  // the same voxels back

  // Picked under the cursor where it was painted, after the paint and after the redo.
  const auto hovers = test::eventsOf(run, "hover");
  REQUIRE(hovers.size() == 2);
  for (const json& h : hovers) {
    CHECK(h["structure"] == "patch");
    CHECK(h.contains("highlight_rgb"));
  }
  // Its distance field was computed on the painted labels (the whole volume needs none).
  const auto fields = test::eventsOf(run, "field");
  REQUIRE_FALSE(fields.empty());
  CHECK(fields.back()["structure"] == "patch");
}

namespace {

// The mean colour of the (2r+1)² pixels around (x, y).
std::array<double, 3> meanAround(const RgbImage& image, int x, int y, int r) {
  std::array<double, 3> sum{0, 0, 0};
  int n = 0;
  for (int j = y - r; j <= y + r; ++j)
    for (int i = x - r; i <= x + r; ++i) {
      if (i < 0 || j < 0 || i >= image.width || j >= image.height) continue;
      const std::size_t at = (std::size_t(j) * std::size_t(image.width) + std::size_t(i)) * 3;
      for (std::size_t c = 0; c < 3; ++c) sum[c] += image.rgb[at + c];
      ++n;
    }
  for (double& v : sum) v /= std::max(1, n);
  return sum;
}

double distance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  return std::sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

}  // namespace

TEST_CASE("desktop (Xvfb, 1280 x 720): the painted label shows in the 3-D view in its highlight colour; undo hides it, redo shows it") {
  if (!test::requireXvfb()) return;
  test::TempDir dir;
  const fs::path box = test::writeBox(dir);
  const fs::path before = dir / "before.png", painted = dir / "painted.png", undone = dir / "undone.png",
                 redone = dir / "redone.png";
  // The editor docks at the right at this size: the view's centre lies between the two columns.
  const json settle = {{"do", "wait_field"}, {"timeout_ms", 120000}};
  const json actions = json::array({
      {{"do", "segment_open"}},
      {{"do", "wait"}, {"ms", 30}},  // the next frame's layout docks the editor
      {{"do", "view"}, {"value", "anterior"}},
      {{"do", "segment_label"}, {"name", "patch"}},
      {{"do", "segment_tool"}, {"tool", "paint"}, {"brush_mm", 4.0}},
      {{"do", "layout"}},
      settle,
      {{"do", "screenshot"}, {"path", before.string()}},
      {{"do", "click"}, {"view_at", {0.5, 0.5}}},
      settle,
      {{"do", "screenshot"}, {"path", painted.string()}},
      {{"do", "segment_undo"}},
      settle,
      {{"do", "screenshot"}, {"path", undone.string()}},
      {{"do", "segment_redo"}},
      settle,
      {{"do", "screenshot"}, {"path", redone.string()}},
  });
  test::DesktopOptions options;
  options.dataset = box.string();
  options.size = "1280x720";
  options.renderScale = 0.5;
  const auto run = test::runDesktopScript(dir, {{"actions", actions}}, options);
  INFO(run.err);
  REQUIRE(run.exitCode == 0);
  const auto layouts = test::eventsOf(run, "layout");
  REQUIRE(layouts.size() == 1);
  CHECK(layouts[0]["editor_docked"] == true);
  CHECK(layouts[0]["slices_docked"] == true);
  const json& view = layouts[0]["view"];  // {x, y, width, height} in window pixels
  CHECK(view["width"].get<double>() >= 400);
  const int cx = int(view["x"].get<double>() + 0.5 * view["width"].get<double>()),
            cy = int(0.5 * view["height"].get<double>());
  const auto edits = test::eventsOf(run, "segment_edited");
  REQUIRE(edits.size() == 1);
  CHECK(edits[0]["tool"] == "paint");
  CHECK(test::eventsOf(run, "labels_shown").size() == 4);  // added, painted, undone, redone

  auto a = readPng(before.string()), b = readPng(painted.string()), c = readPng(undone.string()), d = readPng(redone.string());
  REQUIRE(a);
  REQUIRE(b);
  REQUIRE(c);
  REQUIRE(d);
  const auto base = meanAround(*a, cx, cy, 4), paint = meanAround(*b, cx, cy, 4), undo = meanAround(*c, cx, cy, 4),
             redo = meanAround(*d, cx, cy, 4);
  CAPTURE(base[0]);
  CAPTURE(base[1]);
  CAPTURE(base[2]);
  CAPTURE(paint[0]);
  CAPTURE(paint[1]);
  CAPTURE(paint[2]);
  // The structure's highlight: the derived presets' orange (red well above blue), not the box's grey.
  CHECK(paint[0] > paint[2] + 60);
  CHECK(distance(paint, base) > 60);
  CHECK(distance(undo, base) < 12);   // undone: the whole volume as before
  CHECK(distance(redo, paint) < 12);  // redone: the structure again
}

TEST_CASE("layout: the expert panel and the segment editor dock at the right and the slice panes under the view where the view keeps room") {
  for (const auto& [w, h] : {std::pair{1280, 720}, std::pair{1920, 1080}}) {
    CAPTURE(w);
    app::ViewLayout l;
    l.windowW = l.framebufferW = w;
    l.windowH = l.framebufferH = h;
    l.panelPx = w >= 1200 ? 380 : 320;  // the explore panel's default widths
    app::dockPanels(l, true, true);
    CHECK(l.rightPx >= 340);
    CHECK(l.viewWidth() >= app::kMinDockedViewPx);
    CHECK(l.bottomPx > 100);
    CHECK(l.viewHeight() >= 0.6 * h);
    CHECK(l.viewLeft() + l.viewWidth() + l.rightPx == doctest::Approx(w));
    CHECK(l.inView(l.viewLeft() + l.viewWidth() / 2, l.viewHeight() / 2));
    CHECK_FALSE(l.inView(w - l.rightPx / 2, 10));  // on the editor
    CHECK_FALSE(l.inView(l.viewLeft() + 10, h - 10));  // on the slice panes
    CHECK(l.viewPixelsW() == int(std::lround(l.viewWidth())));
    app::dockPanels(l, true, false);  // the editor without the slices: the view full height
    CHECK(l.bottomPx == 0);
    CHECK(l.rightPx > 0);
    app::dockPanels(l, false, true);  // no editor: nothing docked
    CHECK(l.rightPx == 0);
    CHECK(l.bottomPx == 0);
  }
  for (const auto& [w, h] : {std::pair{1280, 720}, std::pair{1920, 1080}}) {  // the expert panel, alone and with the editor
    CAPTURE(w);
    app::ViewLayout l;
    l.windowW = l.framebufferW = w;
    l.windowH = l.framebufferH = h;
    l.panelPx = w >= 1200 ? 380 : 320;
    app::dockPanels(l, false, false, true);
    CHECK(l.expertPx == app::kExpertPanelPx);
    CHECK(l.rightPx == 0);
    CHECK(l.viewLeft() + l.viewWidth() + l.expertPx == doctest::Approx(w));  // the view ends where the panel starts
    CHECK_FALSE(l.inView(w - l.expertPx / 2, 10));
    app::dockPanels(l, true, true, true);
    CHECK(l.expertPx == app::kExpertPanelPx);
    if (l.rightPx > 0) {  // both columns only where the view keeps its room
      CHECK(l.viewWidth() >= app::kMinDockedViewPx);
      CHECK(l.viewLeft() + l.viewWidth() + l.rightPx + l.expertPx == doctest::Approx(w));
    } else {
      CHECK(w < 1500);
      CHECK(l.bottomPx == 0);
    }
  }
  app::ViewLayout small;  // too narrow for a docked column: floating windows, the view whole
  small.windowW = small.framebufferW = 800;
  small.windowH = small.framebufferH = 480;
  app::dockPanels(small, true, true, true);
  CHECK(small.rightPx == 0);
  CHECK(small.expertPx == 0);
  CHECK(small.viewWidth() == doctest::Approx(800 - 320));
}
