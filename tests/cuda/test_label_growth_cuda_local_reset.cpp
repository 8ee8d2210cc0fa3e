// The GPU growth's local reset (cuda/src/growth_local_reset.cuh): removing or relabelling seeds
// resets the voxels that grew from them — the same voxels the CPU engine finds on the same pairs —
// and the growth then equals the CPU engine's and the exact reference bit for bit. Without a device
// every case prints "SKIPPED: no CUDA device (<reason>)" and passes.
#include <doctest/doctest.h>

#include <cstring>
#include <map>
#include <random>
#include <set>

#include "cuda/wdt_cuda.h"
#include "growth_cases.h"
#include "test_support.h"
#include "wdt/label_growth.h"

using namespace at;
using namespace at::test;

namespace {

// `count` one-voxel seeds at distinct voxels, labels taken in turn from `labels`.
std::vector<GrowthSeed> scatteredSeeds(std::mt19937_64& rng, Dims dims, const std::vector<std::uint16_t>& labels,
                                       std::size_t count) {
  std::vector<GrowthSeed> seeds;
  std::set<std::size_t> taken;
  std::uniform_int_distribution<std::size_t> voxel(0, dims.count() - 1);
  while (seeds.size() < count) {
    const std::size_t v = voxel(rng);
    if (taken.insert(v).second) seeds.push_back({v, labels[seeds.size() % labels.size()]});
  }
  return seeds;
}

std::size_t seedsOf(const std::vector<GrowthSeed>& seeds, std::uint16_t label) {
  return std::size_t(std::count_if(seeds.begin(), seeds.end(), [&](const GrowthSeed& s) { return s.label == label; }));
}

std::size_t voxelsOf(const LabelGrowth& growth, std::uint16_t label) {
  return std::size_t(std::count(growth.labels().voxels.begin(), growth.labels().voxels.end(), label));
}

constexpr std::size_t kNoVoxel = ~std::size_t(0);

struct Updated {
  GrowthStats gpu, cpu;
};

// Updates both growths; labels, distances and the voxels reset are the same.
Updated updateBoth(LabelGrowth& gpu, LabelGrowth& cpu, const std::vector<GrowthSeed>& seeds) {
  auto g = gpu.update(seeds);
  REQUIRE(g);
  auto c = cpu.update(seeds);
  REQUIRE(c);
  CHECK(toString(g->backendUsed) == std::string("cuda"));
  CHECK(g->converged);
  CHECK(c->converged);
  CHECK(g->voxelsReset == c->voxelsReset);
  CHECK(gpu.labels().voxels == cpu.labels().voxels);
  auto dg = gpu.distances();
  auto dc = cpu.distances();
  REQUIRE(dg);
  REQUIRE(dc);
  CHECK(std::memcmp(dg->voxels.data(), dc->voxels.data(), dg->voxels.size() * sizeof(float)) == 0);
  return {*g, *c};
}

}  // namespace

TEST_CASE("GPU: removing or relabelling seeds resets only what grew from them, as the CPU does, and equals the exact growth") {
  const auto& info = cuda::queryDevice();
  if (!info.available) {
    skipf("no CUDA device (%s)", info.reason.c_str());
    return;
  }
  std::mt19937_64 rng(freshSeed("cuda growth local reset"));
  // Grids across several bricks (16³) and not multiples of them; few seeds a label on the larger
  // ones, so that what grew from one seed spans bricks and the search runs many levels.
  const struct {
    Dims dims;
    std::size_t seeds;
  } cases[] = {{{48, 40, 36}, 60}, {{75, 45, 38}, 36}, {{33, 5, 70}, 30}};
  const std::vector<std::uint16_t> labels = {0, 7, 12};
  for (const auto& c : cases) {
    CAPTURE(c.dims.toString());
    const Volume volume = randomVolume(rng, c.dims);
    GrowthParams params = randomParams(rng);
    CAPTURE(toString(params.weight));
    CAPTURE(toString(params.rule));
    std::vector<GrowthSeed> seeds = scatteredSeeds(rng, c.dims, labels, c.seeds);
    params.backend = WdtBackend::Cuda;
    auto gpu = LabelGrowth::create(volume, params);
    REQUIRE(gpu);
    params.backend = WdtBackend::Cpu;
    auto cpu = LabelGrowth::create(volume, params);
    REQUIRE(cpu);
    updateBoth(*gpu, *cpu, seeds);
    for (int step = 0; step < 5; ++step) {
      CAPTURE(step);
      // One seed relabelled and one or two removed, each from a label that keeps at least two
      // seeds (so the edited labels keep voxels no removed seed reaches: their kept seeds); a step
      // edits fewer where no label has seeds to spare.
      std::vector<GrowthSeed> next = seeds;
      std::set<std::uint16_t> edited;
      std::size_t relabelled = kNoVoxel, changed = 0;
      for (int r = 0, removals = 1 + int(rng() % 2); r <= removals; ++r) {
        std::vector<std::size_t> candidates;
        for (std::size_t i = 0; i < next.size(); ++i)
          if (next[i].index != relabelled && seedsOf(next, next[i].label) > 2) candidates.push_back(i);
        if (candidates.empty()) break;
        ++changed;
        const std::size_t i = candidates[rng() % candidates.size()];
        edited.insert(next[i].label);
        if (r == 0) {
          relabelled = next[i].index;
          next[i].label = labels[(std::find(labels.begin(), labels.end(), next[i].label) - labels.begin() + 1) % 3];
        } else {
          next.erase(next.begin() + std::ptrdiff_t(i));
        }
      }
      std::size_t ofEditedLabels = 0;
      for (std::uint16_t l : edited) ofEditedLabels += voxelsOf(*gpu, l);
      REQUIRE(changed > 0);
      const Updated u = updateBoth(*gpu, *cpu, next);
      CHECK(u.gpu.voxelsReset >= changed);  // the edited seeds' own voxels at least
      CHECK(u.gpu.voxelsReset < ofEditedLabels);
      MESSAGE("reset " << u.gpu.voxelsReset << " voxels of " << ofEditedLabels << " in the edited labels");
      requireEqualToExact(*gpu, volume, next, params);
      seeds = next;
    }
    // Every seed of one label removed: every voxel of that label grew from them, so all are reset.
    // (Not label 0: the label map reads unreached voxels as 0 too.)
    const std::uint16_t gone = labels[1 + rng() % (labels.size() - 1)];
    const std::size_t ofGone = voxelsOf(*gpu, gone);
    std::vector<GrowthSeed> next;
    for (const GrowthSeed& s : seeds)
      if (s.label != gone) next.push_back(s);
    const Updated u = updateBoth(*gpu, *cpu, next);
    CHECK(u.gpu.voxelsReset == ofGone);
    CHECK(voxelsOf(*gpu, gone) == 0);
    requireEqualToExact(*gpu, volume, next, params);
  }
}
