// Analytic cases of the weighted distance transform: chamfer distances, a wall with a hole,
// anisotropic spacing, density vs uniform weights.
#include <doctest/doctest.h>

#include <cmath>

#include "wdt/stencil.h"
#include "wdt/wdt.h"

using namespace at;

namespace {

constexpr float kAirHu = -1000.0f, kBoneHu = 2000.0f;

Geometry cube(int nx, int ny, int nz, Vec3 spacing = {1, 1, 1}) {
  Geometry g;
  g.dims = {nx, ny, nz};
  g.spacingMm = spacing;
  return g;
}

WdtParams cpuParams(WeightRule weight = WeightRule::Density, bool converge = true) {
  WdtParams p;
  p.backend = WdtBackend::Cpu;
  p.weight = weight;
  p.converge = converge;
  return p;
}

FloatVolume sweepField(const Volume& v, const Mask& m, const WdtParams& p) {
  auto r = computeWdt(v, m, p);
  if (!r) FAIL(r.error().message);
  return r->field.distances;
}

}  // namespace

TEST_CASE("Uniform weights from one seed voxel give the 26-neighbour chamfer distances") {
  const Geometry g = cube(9, 9, 9);
  Volume v(g, std::int16_t(0));
  Mask m(g, 0);
  m.at(4, 4, 4) = 1;
  const float s2 = std::sqrt(2.0f), s3 = std::sqrt(3.0f);
  //  offsets from the seed and their chamfer lengths: straight 1, face diagonal √2, cube diagonal √3
  struct Case { int dx, dy, dz; float expected; };
  const Case cases[] = {{0, 0, 0, 0.0f},        {1, 0, 0, 1.0f},           {0, -1, 0, 1.0f},
                        {1, 1, 0, s2},          {1, -1, 1, s3},            {2, 1, 0, 1 + s2},
                        {3, 2, 1, s3 + s2 + 1}, {-4, -4, -4, 4 * s3},      {4, 0, -2, 2 * s2 + 2}};
  for (bool converge : {false, true}) {
    const FloatVolume sweeps = sweepField(v, m, cpuParams(WeightRule::Uniform, converge));
    auto exact = exactWdt(v, m, cpuParams(WeightRule::Uniform));
    REQUIRE(exact);
    for (const Case& c : cases) {
      CAPTURE(c.dx);
      CAPTURE(c.dy);
      CAPTURE(c.dz);
      CHECK(sweeps.at(4 + c.dx, 4 + c.dy, 4 + c.dz) == doctest::Approx(c.expected).epsilon(1e-6));
      CHECK(exact->at(4 + c.dx, 4 + c.dy, 4 + c.dz) == doctest::Approx(c.expected).epsilon(1e-6));
    }
  }
}

// A 2-D slice (z = 1 voxel), dense wall at x = 10 with one air hole at y = 10:
//
//   y=10  . . . . . . . . . . o . . . . . . . . . .     o = hole
//   y=2   . . . . . S . . . . # . . . . T . . . . .     S = seed (5,2), T = target (15,2)
//                             x=10
TEST_CASE("A dense wall with one hole routes the distance behind it through the hole") {
  const Geometry g = cube(21, 21, 1);
  Volume v(g, std::int16_t(kAirHu));
  for (int y = 0; y < 21; ++y) v.at(10, y, 0) = std::int16_t(kBoneHu);
  Mask m(g, 0);
  m.at(5, 2, 0) = 1;
  const WdtParams p = cpuParams();
  const float air = wdt::densityWeight(0, p.baseCost), bone = wdt::densityWeight(255, p.baseCost);

  // Closed wall: the cheapest path crosses it straight, 9 air steps and one bone step.
  const FloatVolume closed = sweepField(v, m, p);
  CHECK(closed.at(15, 2, 0) == doctest::Approx(9 * air + bone).epsilon(1e-5));

  // With the hole: (5,2) → (10,10) is 5 diagonal + 3 straight steps, and the same back to (15,2).
  v.at(10, 10, 0) = std::int16_t(kAirHu);
  const FloatVolume open = sweepField(v, m, p);
  const float viaHole = air * (10 * std::sqrt(2.0f) + 6);
  CHECK(open.at(15, 2, 0) == doctest::Approx(viaHole).epsilon(1e-5));
  CHECK(open.at(15, 2, 0) < 0.5f * closed.at(15, 2, 0));
  auto exact = exactWdt(v, m, p);
  REQUIRE(exact);
  CHECK(exact->at(15, 2, 0) == doctest::Approx(viaHole).epsilon(1e-5));
}

TEST_CASE("Anisotropic spacing gives physical step lengths and scales the field linearly") {
  const Geometry g = cube(9, 7, 5, {0.5, 1.0, 2.0});
  Volume v(g, std::int16_t(0));
  Mask m(g, 0);
  m.at(4, 3, 2) = 1;
  const FloatVolume d = sweepField(v, m, cpuParams(WeightRule::Uniform));
  CHECK(d.at(6, 3, 2) == doctest::Approx(1.0).epsilon(1e-6));                       // 2 × 0.5 mm
  CHECK(d.at(4, 4, 2) == doctest::Approx(1.0).epsilon(1e-6));                       // 1 × 1 mm
  CHECK(d.at(4, 3, 3) == doctest::Approx(2.0).epsilon(1e-6));                       // 1 × 2 mm
  CHECK(d.at(5, 4, 2) == doctest::Approx(std::sqrt(0.25 + 1.0)).epsilon(1e-6));     // x–y diagonal
  CHECK(d.at(5, 4, 3) == doctest::Approx(std::sqrt(0.25 + 1.0 + 4.0)).epsilon(1e-6));

  // Doubling every spacing doubles every distance (density weights, random-ish HU).
  Volume ct(g);
  for (std::size_t i = 0; i < ct.voxels.size(); ++i) ct.voxels[i] = std::int16_t(int(i * 7919 % 3000) - 1000);
  const FloatVolume a = sweepField(ct, m, cpuParams());
  Volume ct2 = ct;
  ct2.geometry.spacingMm = {1.0, 2.0, 4.0};
  Mask m2 = m;
  m2.geometry = ct2.geometry;
  const FloatVolume b = sweepField(ct2, m2, cpuParams());
  for (std::size_t i = 0; i < a.voxels.size(); ++i) CHECK(b.voxels[i] == doctest::Approx(2 * a.voxels[i]).epsilon(1e-5));
}

TEST_CASE("Uniform weights differ from density weights near dense bone") {
  // A bone shell around the seed's neighbourhood: density distances grow sharply across it,
  // uniform distances do not notice it.
  const Geometry g = cube(15, 15, 15);
  Volume v(g, std::int16_t(kAirHu));
  for (int k = 0; k < 15; ++k)
    for (int j = 0; j < 15; ++j)
      for (int i = 0; i < 15; ++i) {
        const int r = std::max({std::abs(i - 7), std::abs(j - 7), std::abs(k - 7)});
        if (r == 4) v.at(i, j, k) = std::int16_t(kBoneHu);
      }
  Mask m(g, 0);
  m.at(7, 7, 7) = 1;
  const FloatVolume density = sweepField(v, m, cpuParams());
  const FloatVolume uniform = sweepField(v, m, cpuParams(WeightRule::Uniform));
  const float inside = density.at(9, 7, 7) / uniform.at(9, 7, 7);    // air inside the shell
  const float outside = density.at(13, 7, 7) / uniform.at(13, 7, 7); // behind the bone shell
  CHECK(inside == doctest::Approx(0.02).epsilon(1e-4));
  CHECK(outside > 5 * inside);
  CHECK(uniform.at(13, 7, 7) == doctest::Approx(6.0).epsilon(1e-6));
}
