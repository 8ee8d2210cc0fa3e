// Multi-label growth on the GPU: labels and distances equal the CPU engine's and the exact
// reference's bit for bit (random volumes, every weight rule, grids that are not multiples of the
// 16³ bricks), incremental updates included. Without a device every case prints
// "SKIPPED: no CUDA device (<reason>)" and passes.
#include <doctest/doctest.h>

#include <cstdio>
#include <cstring>
#include <random>

#include "cuda/wdt_cuda.h"
#include "growth_cases.h"
#include "test_support.h"
#include "wdt/label_growth.h"

using namespace at;
using namespace at::test;

namespace {

bool requireGrowthDevice() {
  const auto& info = cuda::queryDevice();
  if (!info.available) {
    at::test::skipf("no CUDA device (%s)", info.reason.c_str());
    return false;
  }
  return true;
}

// CUDA and CPU growths of the same volume and params, updated together.
struct GrowthPair {
  LabelGrowth gpu, cpu;
};

GrowthPair makePair(const Volume& volume, GrowthParams params) {
  params.backend = WdtBackend::Cuda;
  auto gpu = LabelGrowth::create(volume, params);
  REQUIRE(gpu);
  params.backend = WdtBackend::Cpu;
  auto cpu = LabelGrowth::create(volume, params);
  REQUIRE(cpu);
  return {std::move(*gpu), std::move(*cpu)};
}

void requireSameAsCpu(GrowthPair& pair, const std::vector<GrowthSeed>& seeds) {
  auto g = pair.gpu.update(seeds);
  REQUIRE(g);
  CHECK(toString(g->backendUsed) == std::string("cuda"));
  CHECK(g->converged);
  auto c = pair.cpu.update(seeds);
  REQUIRE(c);
  CHECK(pair.gpu.labels().voxels == pair.cpu.labels().voxels);
  auto dg = pair.gpu.distances();
  auto dc = pair.cpu.distances();
  REQUIRE(dg);
  REQUIRE(dc);
  CHECK(std::memcmp(dg->voxels.data(), dc->voxels.data(), dg->voxels.size() * sizeof(float)) == 0);
}

}  // namespace

TEST_CASE("Grow from seeds on the GPU equals the CPU and the exact reference bit for bit") {
  if (!requireGrowthDevice()) return;
  std::mt19937_64 rng(freshSeed("cuda growth vs cpu"));
  const Dims sizes[] = {{1, 1, 1}, {17, 1, 9}, {16, 16, 16}, {33, 20, 7}, {40, 37, 35}, {70, 9, 18}, {97, 64, 50}};
  for (const Dims& dims : sizes) {
    const Volume volume = randomVolume(rng, dims);
    const GrowthParams params = randomParams(rng);
    const int labels = dims.count() < 2 ? 1 : std::uniform_int_distribution<int>(2, 8)(rng);
    const std::vector<GrowthSeed> seeds = randomSeeds(rng, dims, labels, std::max(labels, int(dims.count() / 400) + 2));
    CAPTURE(dims.toString());
    CAPTURE(toString(params.weight));
    CAPTURE(toString(params.rule));
    GrowthPair pair = makePair(volume, params);
    requireSameAsCpu(pair, seeds);
    requireEqualToExact(pair.gpu, volume, seeds, params);
  }
}

// A brick made only of seeds lowers nothing itself; the bricks whose halo holds its seeds must still
// be visited, on the first growth and when the seeds are added to an earlier one.
TEST_CASE("GPU: seeds filling a brick grow into the bricks beside it, from scratch and incrementally") {
  if (!requireGrowthDevice()) return;
  Volume volume = repeatingRampVolume({18, 17, 3});
  const Geometry& g = volume.geometry;
  GrowthParams params;
  params.baseCost = 0.05f;
  std::vector<GrowthSeed> seeds;
  for (int z = 0; z < 3; ++z)
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 16; ++x) seeds.push_back({g.dims.index(x, y, z), std::uint16_t(1 + (y % 2))});
  GrowthPair fresh = makePair(volume, params);
  requireSameAsCpu(fresh, seeds);
  requireEqualToExact(fresh.gpu, volume, seeds, params);
  GrowthPair grown = makePair(volume, params);
  requireSameAsCpu(grown, {seeds.front()});
  requireSameAsCpu(grown, seeds);
  requireEqualToExact(grown.gpu, volume, seeds, params);
}

TEST_CASE("Incremental GPU updates (strokes added, erased, relabelled, cancelled) stay equal to the CPU") {
  if (!requireGrowthDevice()) return;
  std::mt19937_64 rng(freshSeed("cuda growth incremental"));
  const Dims dims{61, 47, 39};
  const Volume volume = randomVolume(rng, dims);
  const GrowthParams params = randomParams(rng);
  std::vector<GrowthSeed> seeds = randomSeeds(rng, dims, 5, 15);
  GrowthPair pair = makePair(volume, params);
  requireSameAsCpu(pair, seeds);
  for (int step = 0; step < 6; ++step) {
    CAPTURE(step);
    std::vector<GrowthSeed> next = seeds;
    if (step % 3 == 0) {
      for (GrowthSeed s : randomSeeds(rng, dims, 2, 2)) {
        s.label = seeds[1].label;
        if (std::none_of(next.begin(), next.end(), [&](const GrowthSeed& o) { return o.index == s.index; })) next.push_back(s);
      }
    } else if (step % 3 == 1) {
      std::shuffle(next.begin(), next.end(), rng);
      next.resize(next.size() - next.size() / 3);
    } else {
      for (std::size_t i = 0; i < next.size(); i += 4) next[i].label = 40;
    }
    if (step == 4) {  // a cancelled update, finished by the next one
      std::atomic<bool> cancel{true};
      WdtControl control;
      control.cancel = &cancel;
      auto cancelled = pair.gpu.update(next, control);
      REQUIRE(cancelled);
      CHECK(cancelled->cancelled);
    }
    requireSameAsCpu(pair, next);
    seeds = next;
  }
  requireEqualToExact(pair.gpu, volume, seeds, params);
}
