// The segment editor's tools on anisotropic grids, undo/redo as compressed deltas, and errors.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "segment/label_editor.h"
#include "synthetic_scans.h"
#include "test_support.h"

using namespace at;
using segment::LabelEditor;

namespace {

Geometry anisotropicGrid() {
  Geometry g;
  g.dims = {40, 36, 24};
  g.spacingMm = {0.5, 0.6, 1.2};
  g.originMm = {-10, 5, 20};
  return g;
}

std::size_t countLabel(const LabelMap& m, std::uint16_t label) {
  std::size_t n = 0;
  for (std::uint16_t v : m.voxels) n += v == label;
  return n;
}

LabelEditor editorWith(const Geometry& g, const std::vector<std::string>& names) {
  LabelEditor editor(LabelMap(g, 0), {});
  for (const std::string& n : names) REQUIRE(editor.addStructure(n));
  return editor;
}

}  // namespace

TEST_CASE("The brush paints a sphere in mm on an anisotropic grid, erases it, and undo/redo restore each step") {
  const Geometry g = anisotropicGrid();
  LabelEditor editor = editorWith(g, {"liver", "spleen"});
  const Vec3 centre = g.indexToPatient({20, 18, 12});
  auto painted = editor.paint(centre, 3.0, 1);
  REQUIRE(painted);
  // Exactly the voxels whose centres lie within 3 mm.
  std::size_t expected = 0;
  for (int k = 0; k < g.dims.z; ++k)
    for (int j = 0; j < g.dims.y; ++j)
      for (int i = 0; i < g.dims.x; ++i) expected += norm(g.indexToPatient({double(i), double(j), double(k)}) - centre) <= 3.0;
  CHECK(painted->changed == expected);
  CHECK(countLabel(editor.labels(), 1) == expected);
  // The sphere is wider in voxels along x (0.5 mm) than along z (1.2 mm).
  CHECK(editor.labels().at(25, 18, 12) == 1);
  CHECK(editor.labels().at(20, 18, 15) == 0);
  REQUIRE(editor.paint(centre + Vec3{1, 0, 0}, 2.0, 2));
  REQUIRE(editor.erase(centre, 1.0, std::uint16_t(2)));
  const LabelMap afterErase = editor.labels();
  CHECK(editor.labels().at(20, 18, 12) == 0);
  REQUIRE(editor.undo());  // the erase
  CHECK(editor.labels().at(20, 18, 12) == 2);
  REQUIRE(editor.undo());  // the spleen stroke
  CHECK(countLabel(editor.labels(), 2) == 0);
  CHECK(countLabel(editor.labels(), 1) == expected);
  REQUIRE(editor.redo());
  REQUIRE(editor.redo());
  CHECK(editor.labels().voxels == afterErase.voxels);
  CHECK(!editor.redo());
  // Errors: outside the grid, a label without a structure.
  auto outside = editor.paint({500, 0, 0}, 1.0, 1);
  REQUIRE(!outside);
  CHECK(outside.error().message.find("outside the 40x36x24 grid") != std::string::npos);
  auto unknown = editor.paint(centre, 1.0, 9);
  REQUIRE(!unknown);
  CHECK((unknown.error().kind == ErrorKind::NotFound));
}

TEST_CASE("Undo stores compressed changes: a brush stroke on a 256^3 map costs bytes, not the map") {
  Geometry g;
  g.dims = {256, 256, 256};
  g.spacingMm = {0.2, 0.2, 0.2};
  LabelEditor editor = editorWith(g, {"structure"});
  for (int s = 0; s < 20; ++s) REQUIRE(editor.paint(g.indexToPatient({100.0 + s, 128, 128}), 1.5, 1));
  const std::size_t mapBytes = g.dims.count() * sizeof(std::uint16_t);
  CHECK(editor.history().size() == 21);  // the structure and 20 strokes
  CHECK(editor.history().bytes() < 64 * 1024);
  CHECK(editor.history().bytes() * 500 < mapBytes);
  MESSAGE("20 brush strokes: " << editor.history().bytes() << " bytes of history against a " << mapBytes
                               << "-byte label map");
}

TEST_CASE("Random edits undo and redo to the very same maps") {
  std::mt19937_64 rng(test::freshSeed("editor undo"));
  const Geometry g = anisotropicGrid();
  LabelEditor editor = editorWith(g, {"a", "b", "c"});
  std::vector<LabelMap> states{editor.labels()};
  std::uniform_int_distribution<int> label(1, 3), op(0, 2);
  std::uniform_real_distribution<double> x(0, 39), y(0, 35), z(0, 23), r(0.3, 4);
  for (int e = 0; e < 25; ++e) {
    const Vec3 c = g.indexToPatient({x(rng), y(rng), z(rng)});
    const std::uint16_t l = std::uint16_t(label(rng));
    Result<segment::EditSummary> s = op(rng) == 0 ? editor.erase(c, r(rng)) : editor.paint(c, r(rng), l);
    REQUIRE(s);
    if (s->changed) states.push_back(editor.labels());
  }
  for (std::size_t i = states.size() - 1; i > 0; --i) {
    REQUIRE(editor.undo());
    CHECK(editor.labels().voxels == states[i - 1].voxels);
  }
  for (std::size_t i = 1; i < states.size(); ++i) {
    REQUIRE(editor.redo());
    CHECK(editor.labels().voxels == states[i].voxels);
  }
}

TEST_CASE("Threshold island: the connected region in range under the point; a minimum diameter cuts a thin bridge") {
  // Two bright blocks joined by a bridge one voxel thick, in a dark volume:
  //   [#######]=[#######]
  Geometry g;
  g.dims = {40, 16, 16};
  g.spacingMm = {0.5, 0.5, 0.5};
  Volume v(g, -1000);
  for (int k = 3; k < 13; ++k)
    for (int j = 3; j < 13; ++j) {
      for (int i = 2; i < 16; ++i) v.at(i, j, k) = 1200;
      for (int i = 24; i < 38; ++i) v.at(i, j, k) = 1200;
    }
  for (int i = 16; i < 24; ++i) v.at(i, 8, 8) = 1200;  // the bridge
  IntensityModel hu;
  LabelEditor editor = editorWith(g, {"bone"});
  const Vec3 left = g.indexToPatient({8, 8, 8});
  auto both = editor.thresholdIsland(v, hu, left, 500, 3000, 1);
  REQUIRE(both);
  CHECK(editor.labels().at(30, 8, 8) == 1);  // through the bridge
  REQUIRE(editor.undo());
  segment::ThresholdOptions cut;
  cut.minDiameterMm = 2.0;  // the bridge is 0.5 mm thick
  auto one = editor.thresholdIsland(v, hu, left, 500, 3000, 1, cut);
  REQUIRE(one);
  CHECK(editor.labels().at(8, 8, 8) == 1);
  CHECK(editor.labels().at(30, 8, 8) == 0);
  CHECK(countLabel(editor.labels(), 1) >= 14 * 10 * 10 - 4 * 10 * 10);  // the block, its edges opened
  auto dark = editor.thresholdIsland(v, hu, g.indexToPatient({20, 2, 2}), 500, 3000, 1);
  REQUIRE(!dark);
  CHECK(dark.error().message.find("outside 500") != std::string::npos);
}

TEST_CASE("Margins grow onto unlabelled voxels and shrink; hollow keeps a shell; opening and closing smooth") {
  Geometry g;
  g.dims = {40, 40, 40};
  g.spacingMm = {0.5, 0.5, 1.0};
  LabelEditor editor = editorWith(g, {"ball", "other"});
  const Vec3 centre = g.indexToPatient({20, 20, 20});
  REQUIRE(editor.paint(centre, 6.0, 1));
  const std::size_t ball = countLabel(editor.labels(), 1);
  REQUIRE(editor.paint(g.indexToPatient({20, 20, 30}), 2.0, 2));  // another structure above it
  const std::size_t other = countLabel(editor.labels(), 2);
  REQUIRE(editor.margin(1, 2.0));
  CHECK(countLabel(editor.labels(), 1) > ball);
  CHECK(countLabel(editor.labels(), 2) == other);  // grow never overwrites another structure
  REQUIRE(editor.undo());
  REQUIRE(editor.margin(1, -2.0));
  CHECK(countLabel(editor.labels(), 1) < ball);
  CHECK(editor.labels().at(20, 20, 20) == 1);
  REQUIRE(editor.undo());
  REQUIRE(editor.hollow(1, 1.5));
  CHECK(editor.labels().at(20, 20, 20) == 0);               // the inside removed …
  CHECK(editor.labels().at(20 + 10, 20, 20) == 1);          // … the shell (5 mm out) kept
  REQUIRE(editor.undo());
  // A speck beside the ball goes with opening; a hole inside it is filled by closing.
  REQUIRE(editor.paint(g.indexToPatient({5, 5, 5}), 0.0, 1));
  LabelMap withHole = editor.labels();
  REQUIRE(editor.erase(centre, 1.0));
  CHECK(editor.labels().at(20, 20, 20) == 0);
  REQUIRE(editor.smooth(1, segment::Smoothing::Closing, 2.0));
  CHECK(editor.labels().at(20, 20, 20) == 1);
  REQUIRE(editor.smooth(1, segment::Smoothing::Opening, 1.0));
  CHECK(editor.labels().at(5, 5, 5) == 0);
  CHECK(editor.labels().at(20, 20, 20) == 1);
}

TEST_CASE("Grow from seeds labels the synthetic µCT's skull, brain and air from a few strokes; a second run is incremental") {
  const FloatVolume uct = test::syntheticMicroCt({48, 44, 40});
  Volume v(uct.geometry);
  for (std::size_t i = 0; i < v.voxels.size(); ++i) v.voxels[i] = std::int16_t(uct.voxels[i]);
  const test::MicroCtLayout m = test::microCtLayout(uct.dims());
  LabelEditor editor = editorWith(uct.geometry, {"skull", "brain"});
  const Dims d = uct.dims();
  const auto at = [&](double i, double j, double k) { return d.index(int(i), int(j), int(k)); };
  // Strokes as a user would draw them on the middle slices: a ring along the skull, a ring in the
  // air around it, a ring inside the brain and a dot at its centre.
  std::vector<GrowthSeed> seeds;
  const auto ring = [&](double grow, std::uint16_t label, int axisA, int axisB) {
    for (int step = 0; step < 24; ++step) {
      const double t = step * 3.14159265358979 / 12;
      double p[3] = {m.centre[0], m.centre[1], m.centre[2]};
      p[axisA] += (m.radius[axisA] + grow) * std::cos(t);
      p[axisB] += (m.radius[axisB] + grow) * std::sin(t);
      seeds.push_back({at(std::clamp(p[0], 0.0, d.x - 1.0), std::clamp(p[1], 0.0, d.y - 1.0),
                          std::clamp(p[2], 0.0, d.z - 1.0)), label});
    }
  };
  ring(-m.shell / 2, 1, 0, 1);
  ring(-m.shell / 2, 1, 0, 2);
  ring(3, 0, 0, 1);
  ring(3, 0, 0, 2);
  ring(-m.shell - 3, 2, 0, 1);
  ring(-m.shell - 3, 2, 0, 2);
  seeds.push_back({at(m.centre[0], m.centre[1], m.centre[2]), 2});
  std::sort(seeds.begin(), seeds.end(), [](const GrowthSeed& a, const GrowthSeed& b) { return a.index < b.index; });
  seeds.erase(std::unique(seeds.begin(), seeds.end(),
                          [](const GrowthSeed& a, const GrowthSeed& b) { return a.index == b.index; }),
              seeds.end());
  GrowthParams params;
  params.backend = WdtBackend::Cpu;
  params.windowMin = 0;
  params.windowMax = 255;
  GrowthStats stats;
  auto grown = editor.growFromSeeds(v, seeds, params, &stats);
  REQUIRE(grown);
  CHECK(!stats.incremental);
  std::size_t right = 0, total = 0;
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const double outer = test::microCtRadius(m, i, j, k), inner = test::microCtRadius(m, i, j, k, m.shell);
        if (std::abs(outer - 1) < 0.08 || std::abs(inner - 1) < 0.08) continue;  // the blurred surfaces
        const std::uint16_t truth = inner < 1 ? 2 : outer < 1 ? 1 : 0;
        ++total;  // the teeth below the skull count as background
        right += editor.labels().at(i, j, k) == truth;
      }
  CHECK(double(right) >= 0.97 * double(total));
  seeds.push_back({at(m.centre[0], m.centre[1] + 3, m.centre[2]), 2});
  auto again = editor.growFromSeeds(v, seeds, params, &stats);
  REQUIRE(again);
  CHECK(stats.incremental);
  REQUIRE(editor.undo());
  REQUIRE(editor.undo());
  CHECK(countLabel(editor.labels(), 1) == 0);
}
