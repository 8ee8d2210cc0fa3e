// Where a student clicks a structure (render/click_point.h): the pixel deepest inside where it lies
// in the picture, checked against brute force on random pictures and on a structure in two parts.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "render/click_point.h"
#include "test_support.h"

using namespace at;
using namespace at::render;

namespace {

// Euclidean distance in cells from cell (x, y) to the nearest cell that does not pick (the cells
// beyond the grid do not).
double depthCells(const PixelGrid& g, int x, int y) {
  double best = std::min({double(x + 1), double(y + 1), double(g.cols - x), double(g.rows - y)});
  for (int yy = 0; yy < g.rows; ++yy)
    for (int xx = 0; xx < g.cols; ++xx)
      if (!g.on[std::size_t(yy * g.cols + xx)]) best = std::min(best, std::hypot(double(xx - x), double(yy - y)));
  return best;
}

PixelGrid discs(int cols, int rows, const std::vector<std::array<double, 3>>& centreAndRadius) {
  PixelGrid g{3, 5, 2, cols, rows, std::vector<char>(std::size_t(cols * rows), 0)};
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols; ++x)
      for (const auto& [cx, cy, r] : centreAndRadius)
        if (std::hypot(x - cx, y - cy) <= r) g.on[std::size_t(y * cols + x)] = 1;
  return g;
}

}  // namespace

TEST_CASE("deepestPixel: the pixel is marked and as deep inside the marked area as any") {
  const std::uint64_t seed = at::test::freshSeed("deepestPixel");
  std::mt19937_64 rng(seed);
  for (int round = 0; round < 300; ++round) {
    const int cols = 1 + int(rng() % 40), rows = 1 + int(rng() % 30);
    std::vector<std::array<double, 3>> parts;
    const int n = int(rng() % 4);
    std::uniform_real_distribution<double> u(0, 1);
    for (int i = 0; i < n; ++i) parts.push_back({u(rng) * cols, u(rng) * rows, u(rng) * 10});
    PixelGrid g = discs(cols, rows, parts);
    for (char& c : g.on)  // speckle: single pixels flipped
      if (rng() % 50 == 0) c = !c;
    CAPTURE(round);
    const auto click = deepestPixel(g);
    const int picking = int(std::count(g.on.begin(), g.on.end(), 1));
    if (picking == 0) {
      CHECK_FALSE(click);
      continue;
    }
    REQUIRE(click);
    const int cx = int(click->x - g.x0) / g.step, cy = int(click->y - g.y0) / g.step;
    REQUIRE(cx >= 0);
    REQUIRE(cy >= 0);
    REQUIRE(cx < cols);
    REQUIRE(cy < rows);
    CHECK(g.on[std::size_t(cy * cols + cx)]);  // on the structure
    CHECK(click->markedPixels == picking * g.step * g.step);
    double deepest = 0;
    for (int y = 0; y < rows; ++y)
      for (int x = 0; x < cols; ++x)
        if (g.on[std::size_t(y * cols + x)]) deepest = std::max(deepest, depthCells(g, x, y));
    const double own = depthCells(g, cx, cy);
    // The chamfer metric (1, √2) is within 8.3 % of the Euclidean one.
    CHECK(own >= deepest / 1.083 - 1e-9);
    CHECK(click->depthPx >= own * g.step - 1e-9);
    CHECK(click->depthPx <= own * g.step * 1.083 + 1e-9);
  }
}

TEST_CASE("deepestPixel: two marked parts give the middle of the wider part, not a pixel between them") {
  // Two labyrinths side by side (radii 6 and 9 cells), their centroid in the gap between them.
  const PixelGrid g = discs(60, 30, {{{12, 15, 6}}, {{40, 15, 9}}});
  const auto click = deepestPixel(g);
  REQUIRE(click);
  CHECK(std::fabs((click->x - g.x0) / g.step - 40) <= 1);
  CHECK(std::fabs((click->y - g.y0) / g.step - 15) <= 1);
  CHECK(click->depthPx >= 8 * g.step);
  // Nothing picks: no click.
  PixelGrid none = g;
  std::fill(none.on.begin(), none.on.end(), 0);
  CHECK_FALSE(deepestPixel(none));
  // A grid that does not match its size is refused, not read past its end.
  PixelGrid broken = g;
  broken.on.pop_back();
  CHECK_FALSE(deepestPixel(broken));
}

TEST_CASE("middleOfStructure: a structure in two parts is clicked in the middle of the wider part as the picture shows it") {
  // Two boxes of one label side by side along x (patient left-right), 4 and 8 voxels wide, seen
  // from the front; their centroid lies in the gap, where nothing of the structure is.
  LabelMap labels;
  labels.geometry.dims = {40, 20, 20};
  labels.geometry.spacingMm = {1, 1, 1};
  labels.voxels.assign(labels.geometry.dims.count(), 0);
  const auto box = [&](int x0, int x1) {
    for (int k = 6; k < 14; ++k)
      for (int j = 6; j < 14; ++j)
        for (int i = x0; i < x1; ++i) labels.voxels[labels.geometry.dims.index(i, j, k)] = 7;
  };
  box(4, 8);
  box(24, 32);
  const Vec3 centre = labels.geometry.indexToPatient({19.5, 9.5, 9.5});
  auto camera = Camera::looking(centre, {0, 1, 0}, {0, 0, 1}, 80);
  REQUIRE(camera);
  const int w = 200, h = 100;
  const auto middle = middleOfStructure(labels, 7, *camera, w, h, std::nullopt, 1);
  REQUIRE(middle);
  const auto wide = camera->project(labels.geometry.indexToPatient({27.5, 9.5, 9.5}), w, h);
  const auto narrow = camera->project(labels.geometry.indexToPatient({5.5, 9.5, 9.5}), w, h);
  const auto gap = camera->project(centre, w, h);
  REQUIRE(wide);
  REQUIRE(narrow);
  REQUIRE(gap);
  const auto pixelsFrom = [&](const std::array<double, 2>& p) { return std::hypot(middle->x - p[0], middle->y - p[1]); };
  const double voxelPx = std::fabs((*wide)[0] - (*camera->project(labels.geometry.indexToPatient({28.5, 9.5, 9.5}), w, h))[0]);
  CAPTURE(voxelPx);
  CHECK(pixelsFrom(*wide) <= 1.5 * voxelPx);
  CHECK(pixelsFrom(*gap) > 5 * voxelPx);
  // The clip plane cuts the wider part away (keeps the side n·p ≤ d): the middle moves to the other.
  const Vec3 cut = labels.geometry.indexToPatient({18, 0, 0});
  auto clip = ClipPlane::fromCoefficients(cut[0] > 0 ? 1 : -1, 0, 0, std::fabs(cut[0]));
  REQUIRE(clip);
  // (which side is kept depends on the grid's orientation: keep the narrow box's)
  if (!clip->keeps(labels.geometry.indexToPatient({5.5, 9.5, 9.5}))) clip = ClipPlane::fromCoefficients(cut[0] > 0 ? -1 : 1, 0, 0, -std::fabs(cut[0]));
  REQUIRE(clip);
  REQUIRE(clip->keeps(labels.geometry.indexToPatient({5.5, 9.5, 9.5})));
  REQUIRE_FALSE(clip->keeps(labels.geometry.indexToPatient({27.5, 9.5, 9.5})));
  const auto clipped = middleOfStructure(labels, 7, *camera, w, h, *clip, 1);
  REQUIRE(clipped);
  // (the narrow box is 4 voxels wide and 8 tall: its deepest pixels run along its middle column)
  CHECK(std::fabs(clipped->x - (*narrow)[0]) <= 1.5 * voxelPx);
  CHECK(std::fabs(clipped->y - (*narrow)[1]) <= 2.5 * voxelPx);
  // A label with no voxels, or out of the picture: no middle.
  CHECK_FALSE(middleOfStructure(labels, 9, *camera, w, h, std::nullopt, 1));
  auto away = Camera::looking(centre + Vec3{0, 0, 500}, {0, 1, 0}, {0, 0, 1}, 80);
  REQUIRE(away);
  CHECK_FALSE(middleOfStructure(labels, 7, *away, w, h, std::nullopt, 1));
}
