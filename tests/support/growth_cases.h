// Random inputs of the multi-label growth shared by the WDT and CUDA suites: blocky random volumes
// on anisotropic grids, stroke-like seeds of several labels, random step rules and weights, and
// the bit-for-bit comparison with the exact reference.
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <cstring>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "wdt/label_growth.h"

namespace at::test {

inline Volume randomVolume(std::mt19937_64& rng, Dims dims) {
  Geometry g;
  g.dims = dims;
  std::uniform_real_distribution<double> sp(0.3, 1.5);
  g.spacingMm = {sp(rng), sp(rng), sp(rng)};
  Volume v(g);
  std::uniform_int_distribution<int> hu(-1000, 2000), block(1, 5);
  const int b = block(rng);
  const int bx = dims.x / b + 1, by = dims.y / b + 1, bz = dims.z / b + 1;
  std::vector<std::int16_t> blockHu(std::size_t(bx) * by * bz);
  for (auto& h : blockHu) h = std::int16_t(hu(rng));
  for (int k = 0; k < dims.z; ++k)
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i)
        v.at(i, j, k) = std::int16_t(std::clamp(blockHu[std::size_t(i / b + bx * (j / b + by * (k / b)))] + hu(rng) / 10, -1024, 3000));
  return v;
}

// A small anisotropic volume of soft-tissue-to-bone values repeating along x (300 … 540 HU), for
// the deterministic brick-face cases: every step has a cost, nothing is out of a bone range.
inline Volume repeatingRampVolume(Dims dims) {
  Geometry g;
  g.dims = dims;
  g.spacingMm = {0.5, 0.7, 1.1};
  Volume v(g);
  for (std::size_t i = 0; i < v.voxels.size(); ++i) v.voxels[i] = std::int16_t(300 + int(i % 7) * 40);
  return v;
}

// Short strokes (runs of voxels along an axis) of random labels; at least two labels.
inline std::vector<GrowthSeed> randomSeeds(std::mt19937_64& rng, Dims d, int labels, int strokes) {
  std::vector<std::uint16_t> values(static_cast<std::size_t>(labels));
  std::uniform_int_distribution<int> value(0, 40);
  std::set<std::uint16_t> used;
  for (auto& l : values) {
    do l = std::uint16_t(value(rng));
    while (used.count(l));
    used.insert(l);
  }
  std::map<std::size_t, std::uint16_t> byVoxel;
  for (int s = 0; s < strokes; ++s) {
    const std::uint16_t label = values[std::size_t(s % labels)];
    int p[3] = {std::uniform_int_distribution<int>(0, d.x - 1)(rng), std::uniform_int_distribution<int>(0, d.y - 1)(rng),
                std::uniform_int_distribution<int>(0, d.z - 1)(rng)};
    const int axis = std::uniform_int_distribution<int>(0, 2)(rng);
    const int n[3] = {d.x, d.y, d.z};
    const int length = std::uniform_int_distribution<int>(1, 6)(rng);
    for (int t = 0; t < length && p[axis] < n[axis]; ++t, ++p[axis]) byVoxel[d.index(p[0], p[1], p[2])] = label;
  }
  std::vector<GrowthSeed> seeds;
  for (const auto& [index, label] : byVoxel) seeds.push_back({index, label});
  return seeds;
}

inline GrowthParams randomParams(std::mt19937_64& rng) {
  GrowthParams p;
  p.backend = WdtBackend::Cpu;
  const WeightRule weights[] = {WeightRule::Gradient, WeightRule::Gradient, WeightRule::Density, WeightRule::Uniform,
                                WeightRule::Ascent};
  p.weight = weights[std::uniform_int_distribution<int>(0, 4)(rng)];
  p.rule = std::uniform_int_distribution<int>(0, 1)(rng) ? StepRule::Trapezoid : StepRule::Entering;
  p.baseCost = std::uniform_real_distribution<float>(0.005f, 0.3f)(rng);
  p.windowMin = float(std::uniform_int_distribution<int>(-1000, 0)(rng));
  p.windowMax = p.windowMin + float(std::uniform_int_distribution<int>(100, 3000)(rng));
  return p;
}

// Bit-for-bit comparison of a growth's result with the exact reference.
inline void requireEqualToExact(const LabelGrowth& growth, const Volume& volume, const std::vector<GrowthSeed>& seeds,
                         const GrowthParams& params) {
  auto exact = exactLabelGrowth(volume, seeds, params);
  REQUIRE(exact);
  auto distances = growth.distances();
  REQUIRE(distances);
  std::size_t distanceDiffs = 0, labelDiffs = 0;
  for (std::size_t i = 0; i < exact->labels.voxels.size(); ++i) {
    distanceDiffs += std::memcmp(&distances->voxels[i], &exact->distances.voxels[i], sizeof(float)) != 0;
    labelDiffs += growth.labels().voxels[i] != exact->labels.voxels[i];
  }
  CHECK(distanceDiffs == 0);
  CHECK(labelDiffs == 0);
}

}  // namespace at::test
