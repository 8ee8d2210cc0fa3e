// Range-limited growth ("bone only", GrowthParams::limitRange): on fresh random volumes the CPU
// engine equals the exact reference bit for bit, no voxel outside the range is taken by growth, and
// every grown voxel is joined to a seed of its label through voxels inside the range.
#include <doctest/doctest.h>

#include <algorithm>
#include <deque>
#include <map>
#include <random>

#include "growth_cases.h"
#include "test_support.h"
#include "wdt/label_growth.h"

using namespace at;
using namespace at::test;

TEST_CASE("Range-limited growth: exact, never enters voxels outside the range, never passes through them") {
  std::mt19937_64 rng(test::freshSeed("range-limited growth"));
  const Dims sizes[] = {{17, 1, 9}, {16, 16, 16}, {33, 20, 7}, {40, 37, 35}};
  for (const Dims& dims : sizes) {
    const Volume volume = randomVolume(rng, dims);
    GrowthParams params = randomParams(rng);
    params.limitRange = true;
    params.rangeMin = float(std::uniform_int_distribution<int>(-1000, 500)(rng));
    params.rangeMax = params.rangeMin + float(std::uniform_int_distribution<int>(200, 2000)(rng));
    const int labels = std::uniform_int_distribution<int>(2, 5)(rng);
    const std::vector<GrowthSeed> seeds = randomSeeds(rng, dims, labels, std::max(labels, int(dims.count() / 400) + 2));
    CAPTURE(dims.toString());
    CAPTURE(params.rangeMin);
    CAPTURE(params.rangeMax);
    auto growth = LabelGrowth::create(volume, params);
    REQUIRE(growth);
    REQUIRE(growth->update(seeds));
    requireEqualToExact(*growth, volume, seeds, params);
    const auto inRange = [&](std::size_t v) {
      return volume.voxels[v] >= params.rangeMin && volume.voxels[v] <= params.rangeMax;
    };
    std::vector<int> seedLabel(dims.count(), -1);
    for (const GrowthSeed& s : seeds) seedLabel[s.index] = s.label;
    // Flood from each seed inside the range through in-range voxels of its label (26-neighbours):
    // every voxel the growth labelled must be reached, or be a seed.
    std::vector<char> reached(dims.count(), 0);
    std::deque<std::size_t> queue;
    for (const GrowthSeed& s : seeds)
      if (growth->labels().voxels[s.index] == s.label) reached[s.index] = 1, queue.push_back(s.index);
    std::size_t outsideTaken = 0, grown = 0;
    while (!queue.empty()) {
      const std::size_t v = queue.front();
      queue.pop_front();
      if (!inRange(v)) continue;  // a seed outside the range does not spread
      const int x = int(v % std::size_t(dims.x)), y = int(v / std::size_t(dims.x) % std::size_t(dims.y)),
                z = int(v / (std::size_t(dims.x) * std::size_t(dims.y)));
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            if (!dims.contains(x + dx, y + dy, z + dz)) continue;
            const std::size_t u = dims.index(x + dx, y + dy, z + dz);
            if (reached[u] || !inRange(u) || growth->labels().voxels[u] != growth->labels().voxels[v]) continue;
            reached[u] = 1;
            queue.push_back(u);
          }
    }
    std::size_t unexplained = 0;
    for (std::size_t v = 0; v < dims.count(); ++v) {
      if (seedLabel[v] >= 0) continue;
      if (!inRange(v)) outsideTaken += growth->labels().voxels[v] != 0;
      else if (growth->labels().voxels[v] != 0 || reached[v]) ++grown, unexplained += !reached[v];
    }
    CHECK(outsideTaken == 0);
    CHECK(unexplained == 0);
    MESSAGE(dims.toString() << ": " << grown << " voxels grown inside the range");
  }
}

TEST_CASE("Range-limited growth refuses an empty range and the cuda backend") {
  Geometry g;
  g.dims = {4, 4, 4};
  const Volume volume(g);
  GrowthParams params;
  params.limitRange = true;
  params.rangeMin = 10;
  params.rangeMax = 5;
  auto bad = LabelGrowth::create(volume, params);
  REQUIRE(!bad);
  CHECK(bad.error().message.find("range limit") != std::string::npos);
  params.rangeMax = 20;
  params.backend = WdtBackend::Cuda;
  auto cuda = LabelGrowth::create(volume, params);
  REQUIRE(!cuda);
  CHECK(cuda.error().message.find("CPU only") != std::string::npos);
}

// A seed on a brick's face lies in the halo of the brick across it. When nothing of its own brick
// is lowered (a brick made only of seeds, or of seeds and voxels outside the range), the growth
// must still reach across: every case equals the exact reference, and the far side is labelled.
TEST_CASE("Seeds on a brick face grow into the next brick though their own brick lowers nothing") {
  Volume volume = repeatingRampVolume({18, 3, 2});
  const Geometry& g = volume.geometry;
  GrowthParams params;
  params.backend = WdtBackend::Cpu;
  params.baseCost = 0.05f;
  SUBCASE("a brick filled with seeds") {
    std::vector<GrowthSeed> seeds;
    for (int z = 0; z < 2; ++z)
      for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 16; ++x) seeds.push_back({g.dims.index(x, y, z), std::uint16_t(1 + (y % 2))});
    for (const bool incremental : {false, true}) {
      CAPTURE(incremental);
      auto growth = LabelGrowth::create(volume, params);
      REQUIRE(growth);
      if (incremental) REQUIRE(growth->update({seeds.front()}));
      REQUIRE(growth->update(seeds));
      requireEqualToExact(*growth, volume, seeds, params);
      for (int z = 0; z < 2; ++z)
        for (int y = 0; y < 3; ++y) CHECK(growth->labels().voxels[g.dims.index(17, y, z)] != 0);
    }
  }
  SUBCASE("a face of seeds behind voxels outside the range") {
    for (int z = 0; z < 2; ++z)
      for (int y = 0; y < 3; ++y) volume.at(14, y, z) = -900;
    params.limitRange = true;
    params.rangeMin = 200;
    params.rangeMax = 1000;
    std::vector<GrowthSeed> seeds;
    for (int z = 0; z < 2; ++z)
      for (int y = 0; y < 3; ++y) seeds.push_back({g.dims.index(15, y, z), 4});
    auto growth = LabelGrowth::create(volume, params);
    REQUIRE(growth);
    REQUIRE(growth->update(seeds));
    requireEqualToExact(*growth, volume, seeds, params);
    for (int z = 0; z < 2; ++z)
      for (int y = 0; y < 3; ++y) {
        CHECK(growth->labels().voxels[g.dims.index(16, y, z)] == 4);
        CHECK(growth->labels().voxels[g.dims.index(13, y, z)] == 0);
      }
  }
}

// The range-limited growths of segment::RangedGrowth copy the ordinary growth's density bytes
// (LabelGrowth::create with sameValues) instead of smoothing the volume again. A growth made so
// equals the exact reference of its own params bit for bit; one whose source was made with other
// smoothing or another window does not take the source's values (it still equals its reference).
TEST_CASE("A growth that copies another growth's values equals the exact reference; other settings' values are not copied") {
  std::mt19937_64 rng(test::freshSeed("growth with copied values"));
  const Dims sizes[] = {{17, 1, 9}, {16, 16, 16}, {33, 20, 7}};
  for (const Dims& dims : sizes) {
    const Volume volume = randomVolume(rng, dims);
    GrowthParams params = randomParams(rng);
    params.smoothingVoxels = std::uniform_real_distribution<float>(0.5f, 1.5f)(rng);
    params.edgeSigma = std::uniform_int_distribution<int>(0, 1)(rng) ? 0.0f : std::uniform_real_distribution<float>(20, 300)(rng);
    GrowthParams limited = params;
    limited.limitRange = true;
    limited.rangeMin = float(std::uniform_int_distribution<int>(-1000, 500)(rng));
    limited.rangeMax = limited.rangeMin + float(std::uniform_int_distribution<int>(200, 2000)(rng));
    const int labels = std::uniform_int_distribution<int>(2, 5)(rng);
    const std::vector<GrowthSeed> seeds = randomSeeds(rng, dims, labels, std::max(labels, int(dims.count() / 400) + 2));
    GrowthParams otherSmoothing = params, otherWindow = params;
    otherSmoothing.smoothingVoxels += 0.75f;
    otherWindow.windowMax += 500.0f;
    CAPTURE(dims.toString());
    CAPTURE(params.smoothingVoxels);
    CAPTURE(params.edgeSigma);
    for (const GrowthParams& sourceParams : {params, otherSmoothing, otherWindow}) {
      auto source = LabelGrowth::create(volume, sourceParams);
      REQUIRE(source);
      REQUIRE(source->update(seeds));
      auto growth = LabelGrowth::create(volume, limited, &*source);
      REQUIRE(growth);
      REQUIRE(growth->update(seeds));
      requireEqualToExact(*growth, volume, seeds, limited);
    }
  }
}

// Bricks (16³) whose every voxel lies outside the range are never visited by the CPU engine (a
// visit could change nothing there). Volumes where whole bricks are out of range, beside bricks
// partly and wholly in range, with seeds in all of them (seeds outside the range keep their label
// and do not spread): the first growth and each later seed edit (seeds added, removed, relabelled)
// equal the exact reference bit for bit.
TEST_CASE("Range-limited growth with whole bricks outside the range: first growth and seed edits equal the exact reference") {
  std::mt19937_64 rng(test::freshSeed("range-limited growth, blocked bricks"));
  const Dims dims{40, 35, 33};  // 3 × 3 × 3 bricks, the last of each axis partial
  Volume volume = randomVolume(rng, dims);
  GrowthParams params = randomParams(rng);
  params.limitRange = true;
  params.rangeMin = 0;
  params.rangeMax = 3000;
  // Every brick: wholly outside the range (−1000), wholly inside (values raised to >= 0), or mixed.
  // The first three bricks take one kind each, so every seed draws all three.
  std::uniform_int_distribution<int> kind(0, 2);
  for (int bz = 0; bz < 3; ++bz)
    for (int by = 0; by < 3; ++by)
      for (int bx = 0; bx < 3; ++bx) {
        const int b = bx + 3 * (by + 3 * bz), k = b < 3 ? b : kind(rng);
        for (int z = bz * 16; z < std::min(dims.z, bz * 16 + 16); ++z)
          for (int y = by * 16; y < std::min(dims.y, by * 16 + 16); ++y)
            for (int x = bx * 16; x < std::min(dims.x, bx * 16 + 16); ++x) {
              std::int16_t& v = volume.at(x, y, z);
              if (k == 0) v = -1000;
              else if (k == 1) v = std::int16_t(std::abs(int(v)));
            }
      }
  const int labels = std::uniform_int_distribution<int>(2, 5)(rng);
  std::vector<GrowthSeed> seeds = randomSeeds(rng, dims, labels, 60);
  auto growth = LabelGrowth::create(volume, params);
  REQUIRE(growth);
  REQUIRE(growth->update(seeds));
  requireEqualToExact(*growth, volume, seeds, params);
  for (int edit = 0; edit < 4; ++edit) {
    CAPTURE(edit);
    std::shuffle(seeds.begin(), seeds.end(), rng);
    seeds.resize(seeds.size() * 3 / 4);  // some removed
    if (edit % 2) seeds.front().label = seeds.back().label;  // one relabelled (maybe to its own label)
    std::map<std::size_t, std::uint16_t> unique;
    for (const GrowthSeed& s : seeds) unique.emplace(s.index, s.label);
    for (const GrowthSeed& s : randomSeeds(rng, dims, labels, 15)) unique.emplace(s.index, s.label);  // some added
    seeds.clear();
    for (const auto& [index, label] : unique) seeds.push_back({index, label});
    REQUIRE(growth->update(seeds));
    requireEqualToExact(*growth, volume, seeds, params);
  }
}
