// The desktop's slice panes: at the voxels' aspect, a click in one pane moving the crosshair (the
// other panes then show the slices through it), labels overlaid at their opacity, the window
// dragged, and a click in the 3-D view moving the crosshair to the structure picked.
#include <doctest/doctest.h>

#include <cmath>

#include "db/connection.h"
#include "headless_desktop.h"
#include "segment_editor/segment_controller.h"
#include "view/slice_views.h"
#include "test_support.h"
#include "volume/slice_image.h"

using namespace at;
using nlohmann::json;

namespace {

// An anisotropic grid with a bright voxel and one label voxel at known places.
Dataset smallDataset() {
  Dataset ds;
  ds.id = "small";
  Geometry g;
  g.dims = {20, 16, 10};
  g.spacingMm = {0.5, 0.5, 2.0};
  ds.volume = Volume(g, std::int16_t(0));
  ds.labels = LabelMap(g, 0);
  ds.volume.at(5, 6, 7) = 1000;
  ds.labels.at(5, 6, 7) = 1;
  Structure s;
  s.label = 1;
  s.id = "spot";
  s.displayName = "Spot";
  s.colour = {0, 1, 0};
  ds.structures.push_back(s);
  return ds;
}

}  // namespace

TEST_CASE("slice panes: aspect from the spacing, a click in one pane moves the others, labels at their opacity") {
  const Dataset ds = smallDataset();
  app::SliceViews slices;
  slices.attach(ds);
  CHECK(slices.crosshair() == std::array<int, 3>{10, 8, 5});
  // Pictures (columns, rows): sagittal (y, z), coronal (x, z), axial (x, y); mm per pixel follows.
  CHECK(slices.pixelMm(0) == std::array<double, 2>{0.5, 2.0});
  CHECK(slices.pixelMm(1) == std::array<double, 2>{0.5, 2.0});
  CHECK(slices.pixelMm(2) == std::array<double, 2>{0.5, 0.5});
  const int scale = 3;
  auto axial = slices.pane(2, scale, &ds.labels, ds.structures);
  REQUIRE(axial);
  CHECK(axial->width == 20 * scale);
  CHECK(axial->height == 16 * scale);
  // A click on the axial pane at voxel (5, 6): the crosshair moves there, keeping its slice z = 5.
  SliceRequest request;
  request.axis = 2;
  request.index = slices.crosshair()[2];
  request.scale = scale;
  REQUIRE(slices.clickPane(2, scale, 5 * scale + 1, 6 * scale + 1));
  CHECK(slices.crosshair() == std::array<int, 3>{5, 6, 5});
  // The coronal pane now shows y = 6; a click on it at (x 5, z 7) puts the crosshair on the spot.
  request.axis = 1;
  request.index = 6;
  const int row = 10 - 1 - 7;  // rows run down from the highest z
  REQUIRE(slices.clickPane(1, scale, 5 * scale + 1, row * scale + 1));
  CHECK(slices.crosshair() == std::array<int, 3>{5, 6, 7});
  CHECK_FALSE(slices.clickPane(1, scale, -4, 2));  // outside the picture: nothing moves
  CHECK(slices.crosshair() == std::array<int, 3>{5, 6, 7});
  // The axial pane through z = 7 shows the spot: bright without labels, green with them opaque.
  slices.labelAlpha = 0;
  axial = slices.pane(2, scale, &ds.labels, ds.structures);
  REQUIRE(axial);
  const std::uint8_t* plain = axial->pixel(5 * scale, 6 * scale);  // a corner of its block, off the crosshair
  CHECK(plain[0] == plain[1]);
  CHECK(plain[0] > 200);
  slices.labelAlpha = 1;
  axial = slices.pane(2, scale, &ds.labels, ds.structures);
  REQUIRE(axial);
  const std::uint8_t* green = axial->pixel(5 * scale, 6 * scale);
  CHECK(green[1] > green[0] + 100);
  // The crosshair's lines: the column and row through the crosshair voxel are yellow.
  const std::uint8_t* line = axial->pixel(5 * scale + scale / 2, 0);
  CHECK((line[0] > 200 && line[1] > 180 && line[2] < 100));
  // A window drag to the right widens it.
  const double width = slices.window()[1];
  slices.dragWindow(100, 0);
  CHECK(slices.window()[1] > width);
  CHECK_FALSE(slices.setCrosshair({20, 0, 0}));
}

TEST_CASE("the segment editor's slice drags the grey window as the Slices window does") {
  const Dataset ds = smallDataset();  // HU: the default window 400 ± 1000
  test::TempDir dir;
  auto database = db::openDatabase((dir / "t.db").string());
  REQUIRE(database);
  app::SegmentController editor(*database, [](json) {});
  editor.attach(ds);
  app::SliceViews slices;
  slices.attach(ds);
  CHECK(editor.greyWindow() == slices.window());
  REQUIRE(editor.setSlice(2, 7));  // through the bright voxel (1000 HU)
  const int scale = 2;
  const auto grey = [&](const RgbImage& image, int i, int j) { return image.pixel(i * scale, j * scale)[0]; };
  auto before = editor.sliceImage(scale, 0.0);
  REQUIRE(before);
  // 0 HU and 1000 HU inside 400 ± 1000: two mid greys.
  const int air = grey(*before, 0, 0), bright = grey(*before, 5, 6);
  CHECK(air > 0);
  CHECK(bright < 255);
  CHECK(bright > air);
  // Narrower (drag left) and centred higher (drag up): 0 HU goes black, 1000 HU white.
  const std::uint64_t revision = editor.revision();
  editor.dragWindow(-300, -60);
  slices.dragWindow(-300, -60);
  CHECK(editor.revision() != revision);
  CHECK(editor.greyWindow() == slices.window());  // one model of the drag, the same numbers
  CHECK(editor.greyWindow()[1] < 2000);
  auto after = editor.sliceImage(scale, 0.0);
  REQUIRE(after);
  CHECK(grey(*after, 0, 0) < air);
  CHECK(grey(*after, 5, 6) > bright);
  // A drag of nothing changes nothing; another dataset starts from its default again.
  const std::uint64_t still = editor.revision();
  editor.dragWindow(0, 0);
  CHECK(editor.revision() == still);
  editor.attach(ds);
  CHECK(editor.greyWindow() == std::array<double, 2>{400, 2000});
}

TEST_CASE("a click in the 3-D view moves the slices' crosshair onto the structure it picked") {
  test::TempDir dir;
  test::HeadlessOptions options;
  options.dataset = "phantom:64";
  options.db = dir / "t.db";
  const json actions = json::array({{{"do", "view"}, {"value", "lateral_right"}},
                                     {{"do", "click_structure"}, {"structure", "tympanic_cavity"}}});
  auto run = test::runHeadless({{"actions", actions}}, options);
  CAPTURE(run.messages);
  REQUIRE(run.exitCode == 0);
  const auto moved = test::eventsOf(run, "crosshair");
  REQUIRE(moved.size() == 1);
  const auto v = moved[0]["voxel"].get<std::vector<int>>();
  CAPTURE(moved[0].dump());
  // What the click picked (the structure in front, from this side, may be another one).
  const auto hovers = test::eventsOf(run, "hover");
  REQUIRE_FALSE(hovers.empty());
  const std::uint16_t picked = hovers.back()["label"].get<std::uint16_t>();
  REQUIRE(picked != 0);
  // The picked point lies on that structure's surface: the crosshair voxel is its or touches it.
  const Dataset& phantom = test::phantomOfSize(64);
  bool near = false;
  for (int dk = -1; dk <= 1; ++dk)
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di)
        if (phantom.labels.dims().contains(v[0] + di, v[1] + dj, v[2] + dk))
          near |= phantom.labels.at(v[0] + di, v[1] + dj, v[2] + dk) == picked;
  CHECK(near);
}

TEST_CASE("slice panes are in patient orientation: the same anatomy stored RAS shows the same panes and letters") {
  const Dataset lps = smallDataset();
  // The same voxels stored with i and j reversed (patient right → left becomes left → right …).
  Dataset ras = lps;
  Geometry g = lps.volume.geometry;
  g.direction.m = {{{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}}};
  g.originMm = lps.volume.geometry.indexToPatient({double(g.dims.x - 1), double(g.dims.y - 1), 0});
  ras.volume = Volume(g, std::int16_t(0));
  ras.labels = LabelMap(g, 0);
  for (int k = 0; k < g.dims.z; ++k)
    for (int j = 0; j < g.dims.y; ++j)
      for (int i = 0; i < g.dims.x; ++i) {
        ras.volume.at(g.dims.x - 1 - i, g.dims.y - 1 - j, k) = lps.volume.at(i, j, k);
        ras.labels.at(g.dims.x - 1 - i, g.dims.y - 1 - j, k) = lps.labels.at(i, j, k);
      }
  REQUIRE(ras.volume.geometry.orientationCode() == "RAS");
  app::SliceViews a, b;
  a.attach(lps);
  b.attach(ras);
  REQUIRE(a.setCrosshair({5, 6, 7}));
  REQUIRE(b.setCrosshair({g.dims.x - 1 - 5, g.dims.y - 1 - 6, 7}));  // the same patient voxel
  const char* letters[3] = {"APSI", "RLSI", "RLAP"};
  for (int plane = 0; plane < 3; ++plane) {
    CAPTURE(plane);
    const SliceLayout la = a.layout(plane), lb = b.layout(plane);
    CHECK(std::string{la.left, la.right, la.top, la.bottom} == letters[plane]);
    CHECK(std::string{lb.left, lb.right, lb.top, lb.bottom} == letters[plane]);
    CHECK(a.pixelMm(plane) == b.pixelMm(plane));
    auto pa = a.pane(plane, 2, &lps.labels, lps.structures);
    auto pb = b.pane(plane, 2, &ras.labels, ras.structures);
    REQUIRE(pa);
    REQUIRE(pb);
    REQUIRE(pa->width == pb->width);
    REQUIRE(pa->height == pb->height);
    CHECK(pa->rgb == pb->rgb);  // pixel for pixel, crosshair lines included
  }
  // A click at the same pixel moves both crosshairs to the same patient point.
  REQUIRE(a.clickPane(2, 2, 3 * 2 + 1, 4 * 2 + 1));
  REQUIRE(b.clickPane(2, 2, 3 * 2 + 1, 4 * 2 + 1));
  const auto& ca = a.crosshair();
  const auto& cb = b.crosshair();
  const Vec3 pa = lps.volume.geometry.indexToPatient({double(ca[0]), double(ca[1]), double(ca[2])});
  const Vec3 pb = g.indexToPatient({double(cb[0]), double(cb[1]), double(cb[2])});
  CHECK(norm(pa - pb) < 1e-6);
}
