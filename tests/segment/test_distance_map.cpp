// Distances in mm on anisotropic grids against brute force, and the ball morphology's properties.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>

#include "segment/distance_map.h"
#include "test_support.h"

using namespace at;

namespace {

Mask randomMask(std::mt19937_64& rng, Dims dims, double fill) {
  Geometry g;
  g.dims = dims;
  std::uniform_real_distribution<double> sp(0.2, 2.5);
  g.spacingMm = {sp(rng), sp(rng), sp(rng)};
  Mask m(g, 0);
  std::bernoulli_distribution on(fill);
  for (auto& v : m.voxels) v = on(rng);
  return m;
}

}  // namespace

TEST_CASE("distanceToMask equals the brute-force Euclidean distance in mm on anisotropic grids") {
  std::mt19937_64 rng(test::freshSeed("distance map"));
  const Dims sizes[] = {{1, 1, 1}, {7, 1, 1}, {9, 8, 1}, {13, 11, 9}, {20, 5, 17}};
  for (const Dims& dims : sizes) {
    for (double fill : {0.0, 0.02, 0.3}) {
      const Mask m = randomMask(rng, dims, fill);
      CAPTURE(dims.toString());
      CAPTURE(fill);
      const FloatVolume d = segment::distanceToMask(m);
      std::size_t wrong = 0;
      for (int k = 0; k < dims.z; ++k)
        for (int j = 0; j < dims.y; ++j)
          for (int i = 0; i < dims.x; ++i) {
            double best = std::numeric_limits<double>::infinity();
            for (int c = 0; c < dims.z; ++c)
              for (int b = 0; b < dims.y; ++b)
                for (int a = 0; a < dims.x; ++a)
                  if (m.at(a, b, c)) {
                    const double dx = (a - i) * m.geometry.spacingMm[0], dy = (b - j) * m.geometry.spacingMm[1],
                                 dz = (c - k) * m.geometry.spacingMm[2];
                    best = std::min(best, std::sqrt(dx * dx + dy * dy + dz * dz));
                  }
            const double got = d.at(i, j, k);
            wrong += std::isinf(best) ? !std::isinf(got) : std::abs(got - best) > 1e-4 * (1 + best);
          }
      CHECK(wrong == 0);
    }
  }
}

TEST_CASE("Opening lies inside the mask and closing around it; a ball of the radius survives opening") {
  std::mt19937_64 rng(test::freshSeed("morphology"));
  for (int round = 0; round < 4; ++round) {
    const Mask m = randomMask(rng, {24, 20, 16}, 0.45);
    const double r = std::uniform_real_distribution<double>(0.5, 3.0)(rng);
    const Mask opened = segment::open(m, r), closed = segment::close(m, r);
    std::size_t outside = 0, lost = 0;
    for (std::size_t i = 0; i < m.voxels.size(); ++i) {
      outside += opened.voxels[i] && !m.voxels[i];
      lost += m.voxels[i] && !closed.voxels[i];
    }
    CHECK(outside == 0);
    CHECK(lost == 0);
  }
  // A ball of radius 4 mm about a voxel centre with a one-voxel spike: opening by the ball's own
  // radius gives back exactly the ball (it is its own structuring element) and drops the spike;
  // opening by 2 mm keeps the centre and most of the ball, and drops the spike too.
  Geometry g;
  g.dims = {30, 30, 30};
  g.spacingMm = {0.5, 0.5, 0.5};
  Mask ball(g, 0);
  const auto inBall = [](int i, int j, int k) { return std::hypot(i - 14, j - 14, k - 14) * 0.5 <= 4.0; };
  for (int k = 0; k < 30; ++k)
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 30; ++i) ball.at(i, j, k) = inBall(i, j, k);
  Mask spiked = ball;
  for (int i = 22; i < 29; ++i) spiked.at(i, 14, 14) = 1;
  CHECK(segment::open(spiked, 4.0).voxels == ball.voxels);
  const Mask opened = segment::open(spiked, 2.0);
  CHECK(opened.at(14, 14, 14) == 1);
  CHECK(opened.at(27, 14, 14) == 0);
  std::size_t kept = 0, total = 0, extra = 0;
  for (int k = 0; k < 30; ++k)
    for (int j = 0; j < 30; ++j)
      for (int i = 0; i < 30; ++i) {
        total += inBall(i, j, k);
        kept += inBall(i, j, k) && opened.at(i, j, k);
        extra += !inBall(i, j, k) && opened.at(i, j, k);
      }
  CHECK(extra == 0);
  CHECK(double(kept) >= 0.9 * double(total));
}
