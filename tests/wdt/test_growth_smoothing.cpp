// The growth's edge-preserving smoothing (wdt/src/growth_smoothing.h) equals its plain definition
// bit for bit: every voxel the weighted mean of its in-grid neighbours within the radius, the taps
// summed in the same order (z, then y, then x offsets ascending), whether the voxel lies in the
// interior (where the fast path skips the bounds checks) or near a face. Random grids from 1 voxel
// thick (no interior) to larger than the neighbourhood on every axis; random sigmas and edge sigmas
// (range weights reaching past, or stopping short of, the values' spread). Prints its seed;
// AT_TEST_SEED replays it.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "growth_smoothing.h"
#include "test_support.h"

using namespace at;

namespace {

std::vector<float> plainBilateral(const Volume& volume, float sigmaVoxels, float edgeSigma) {
  const Dims d = volume.dims();
  const int radius = std::clamp(int(std::ceil(2.0f * sigmaVoxels)), 1, 3);
  const int reach = std::max(1, int(std::ceil(4.0f * edgeSigma)));
  std::vector<float> out(volume.voxels.size());
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const int centre = volume.voxels[d.index(i, j, k)];
        float sum = 0, weight = 0;
        for (int dk = -radius; dk <= radius; ++dk)
          for (int dj = -radius; dj <= radius; ++dj)
            for (int di = -radius; di <= radius; ++di) {
              const int r2 = di * di + dj * dj + dk * dk;
              if (r2 > radius * radius) continue;
              const int x = i + di, y = j + dj, z = k + dk;
              if (x < 0 || y < 0 || z < 0 || x >= d.x || y >= d.y || z >= d.z) continue;
              const int value = volume.voxels[d.index(x, y, z)];
              const int diff = std::abs(value - centre);
              if (diff > reach) continue;
              const float w = std::exp(-0.5f * float(r2) / (sigmaVoxels * sigmaVoxels)) *
                              std::exp(-0.5f * float(diff * diff) / (edgeSigma * edgeSigma));
              sum += w * float(value);
              weight += w;
            }
        out[d.index(i, j, k)] = sum / weight;
      }
  return out;
}

}  // namespace

TEST_CASE("Edge-preserving smoothing equals its plain definition bit for bit, inside the grid and at its faces") {
  const std::uint64_t seed = test::freshSeed("growth smoothing");
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> size(1, 14);
  std::uniform_real_distribution<float> sigma(0.2f, 1.6f), edge(0.5f, 300.0f);
  // Random grids, then two that every seed draws: one with an interior at the largest radius (3)
  // and one 2 voxels thick (faces only).
  std::vector<Dims> grids;
  for (int trial = 0; trial < 24; ++trial) grids.push_back(Dims{size(rng), size(rng), size(rng)});
  grids.push_back(Dims{12, 13, 11});
  grids.push_back(Dims{2, 9, 9});
  for (std::size_t trial = 0; trial < grids.size(); ++trial) {
    const Dims d = grids[trial];
    Volume volume(Geometry{d, {1.0, 0.7, 2.0}}, 0);
    const int spread = std::uniform_int_distribution<int>(1, 3000)(rng);
    std::uniform_int_distribution<int> value(-spread, spread);
    for (auto& v : volume.voxels) v = std::int16_t(value(rng));
    const float s = trial + 2 == grids.size() ? 1.5f : sigma(rng), e = edge(rng);
    CAPTURE(trial);
    CAPTURE(d.toString());
    CAPTURE(s);
    CAPTURE(e);
    const std::vector<float> got = wdt::edgePreservingSmoothed(volume, s, e), want = plainBilateral(volume, s, e);
    REQUIRE(got.size() == want.size());
    std::size_t differ = 0;
    for (std::size_t v = 0; v < got.size(); ++v) differ += std::memcmp(&got[v], &want[v], sizeof(float)) != 0;
    CHECK(differ == 0);
  }
}
