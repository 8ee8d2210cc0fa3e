// Multi-label growth on the CPU against the exact reference (a multi-source Dijkstra with argmin
// labels) on fresh random volumes, the reference against single-label exact fields, the tie rule,
// incremental updates, cancellation and errors.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <map>
#include <random>
#include <set>

#include "growth_cases.h"
#include "test_support.h"
#include "wdt/label_growth.h"
#include "wdt/wdt.h"

using namespace at;
using namespace at::test;

namespace {

struct GrowthCase {
  Volume volume;
  std::vector<GrowthSeed> seeds;
  GrowthParams params;
};

}  // namespace

TEST_CASE("Grow from seeds on the CPU equals the exact multi-source Dijkstra bit for bit, labels included") {
  std::mt19937_64 rng(test::freshSeed("growth vs exact"));
  const Dims sizes[] = {{1, 1, 1}, {3, 1, 1}, {17, 1, 9}, {16, 16, 16}, {33, 20, 7}, {40, 37, 35}, {5, 1, 70}, {70, 9, 18}};
  for (const Dims& dims : sizes) {
    GrowthCase c{randomVolume(rng, dims), {}, randomParams(rng)};
    const int labels = dims.count() < 2 ? 1 : std::uniform_int_distribution<int>(2, 6)(rng);
    c.seeds = randomSeeds(rng, dims, labels, std::max(labels, int(dims.count() / 400) + 2));
    CAPTURE(dims.toString());
    CAPTURE(toString(c.params.rule));
    CAPTURE(toString(c.params.weight));
    CAPTURE(c.params.baseCost);
    CAPTURE(c.seeds.size());
    auto growth = LabelGrowth::create(c.volume, c.params);
    REQUIRE(growth);
    auto stats = growth->update(c.seeds);
    REQUIRE(stats);
    CHECK(stats->converged);
    CHECK(!stats->incremental);
    CHECK(toString(stats->backendUsed) == std::string("cpu"));
    requireEqualToExact(*growth, c.volume, c.seeds, c.params);
  }
}

TEST_CASE("The exact growth is the smallest single-label field, labelled by the smallest label that reaches it") {
  // Independent checks of the reference. Per label, the growth from that label's seeds alone (one
  // label: a plain Dijkstra, where the tie rule plays no part): the multi-label distance is their
  // minimum, and each voxel's label is the smallest label whose own field attains it — the tie rule
  // as stated in label_growth.h. And the fixed-point distances agree with the WDT module's float
  // exact field of all seeds up to the rounding of the step costs.
  std::mt19937_64 rng(test::freshSeed("growth reference vs single-label fields"));
  for (int round = 0; round < 4; ++round) {
    const Dims dims{std::uniform_int_distribution<int>(8, 30)(rng), std::uniform_int_distribution<int>(8, 30)(rng),
                    std::uniform_int_distribution<int>(2, 20)(rng)};
    GrowthCase c{randomVolume(rng, dims), randomSeeds(rng, dims, 3, 9), randomParams(rng)};
    CAPTURE(toString(c.params.weight));
    auto exact = exactLabelGrowth(c.volume, c.seeds, c.params);
    REQUIRE(exact);
    std::map<std::uint16_t, FloatVolume> perLabel;
    for (const GrowthSeed& s : c.seeds) perLabel.try_emplace(s.label);
    for (auto& [label, field] : perLabel) {
      std::vector<GrowthSeed> own;
      for (const GrowthSeed& s : c.seeds)
        if (s.label == label) own.push_back(s);
      auto f = exactLabelGrowth(c.volume, own, c.params);
      REQUIRE(f);
      field = std::move(f->distances);
    }
    WdtParams wp;
    wp.rule = c.params.rule;
    wp.weight = c.params.weight;
    wp.huMin = c.params.windowMin;
    wp.huMax = c.params.windowMax;
    wp.baseCost = c.params.baseCost;
    Mask all(c.volume.geometry, 0);
    for (const GrowthSeed& s : c.seeds) all.voxels[s.index] = 1;
    auto wdt = exactWdt(c.volume, all, wp);
    REQUIRE(wdt);
    std::size_t wrongDistance = 0, wrongLabel = 0;
    double worstRelative = 0;
    for (std::size_t i = 0; i < dims.count(); ++i) {
      float best = INFINITY;
      for (const auto& [label, field] : perLabel) best = std::min(best, field.voxels[i]);
      // Fixed-point distances above 2^24 units can round to the same float, so a label whose field
      // is a unit larger may look tied here. The label must be the one attaining the minimum, or,
      // where several attain it in floats (a true tie or such a collision), one of them; the tie
      // rule itself is checked on mirrored seeds below.
      std::uint16_t smallest = 0xFFFF;
      std::size_t attaining = 0;
      bool exactAttains = false;
      for (const auto& [label, field] : perLabel)
        if (field.voxels[i] == best) {
          smallest = std::min(smallest, label);
          ++attaining;
          exactAttains |= label == exact->labels.voxels[i];
        }
      wrongDistance += exact->distances.voxels[i] != best;
      if (best == INFINITY) wrongLabel += exact->labels.voxels[i] != 0;
      else if (attaining == 1) wrongLabel += exact->labels.voxels[i] != smallest;
      else wrongLabel += !exactAttains;
      const double w = wdt->voxels[i];
      if (w > 0) worstRelative = std::max(worstRelative, std::abs(exact->distances.voxels[i] - w) / w);
    }
    CHECK(wrongDistance == 0);
    CHECK(wrongLabel == 0);
    CHECK(worstRelative < 1e-4);
  }
}

TEST_CASE("Tie rule: a voxel that two seeds reach at the same distance takes the smaller label") {
  // A volume symmetric under x → nx − 1 − x with mirrored seeds of labels 7 and 3: every voxel of
  // the middle plane is reached from both at bit-identical distances (mirrored paths add the same
  // floats in the same order), so all of them must be 3; the two halves mirror each other.
  //   x:   0 … 7 | 8 | 9 … 16        seeds of 7 on the left, of 3 mirrored on the right
  std::mt19937_64 rng(test::freshSeed("growth tie rule"));
  Geometry g;
  g.dims = {17, 12, 9};
  g.spacingMm = {0.7, 1.1, 0.9};
  Volume v(g);
  std::uniform_int_distribution<int> hu(-1000, 1500);
  for (int k = 0; k < g.dims.z; ++k)
    for (int j = 0; j < g.dims.y; ++j)
      for (int i = 0; i <= 8; ++i) v.at(i, j, k) = v.at(16 - i, j, k) = std::int16_t(hu(rng));
  std::vector<GrowthSeed> seeds;
  for (int t = 0; t < 4; ++t) {
    const int i = std::uniform_int_distribution<int>(0, 7)(rng), j = std::uniform_int_distribution<int>(0, 11)(rng),
              k = std::uniform_int_distribution<int>(0, 8)(rng);
    seeds.push_back({g.dims.index(i, j, k), 7});
    seeds.push_back({g.dims.index(16 - i, j, k), 3});
  }
  for (WeightRule weight : {WeightRule::Gradient, WeightRule::Density, WeightRule::Uniform}) {
    CAPTURE(toString(weight));
    GrowthParams p;
    p.weight = weight;
    p.backend = WdtBackend::Cpu;
    auto growth = LabelGrowth::create(v, p);
    REQUIRE(growth);
    REQUIRE(growth->update(seeds));
    auto exact = exactLabelGrowth(v, seeds, p);
    REQUIRE(exact);
    std::size_t middleNot3 = 0, notMirrored = 0, exactMiddleNot3 = 0;
    for (int k = 0; k < g.dims.z; ++k)
      for (int j = 0; j < g.dims.y; ++j) {
        middleNot3 += growth->labels().at(8, j, k) != 3;
        exactMiddleNot3 += exact->labels.at(8, j, k) != 3;
        for (int i = 0; i < 8; ++i) {
          const std::uint16_t left = growth->labels().at(i, j, k), right = growth->labels().at(16 - i, j, k);
          notMirrored += !((left == 7 && right == 3) || (left == 3 && right == 7) || (left == 3 && right == 3));
        }
      }
    CHECK(middleNot3 == 0);
    CHECK(exactMiddleNot3 == 0);
    CHECK(notMirrored == 0);
  }
  // The simplest tie: a row of 5 voxels, seeds at both ends.
  Geometry row;
  row.dims = {5, 1, 1};
  Volume flat(row, 0);
  GrowthParams p;
  p.backend = WdtBackend::Cpu;
  for (auto [left, right] : {std::pair<int, int>{4, 9}, {9, 4}}) {
    auto growth = LabelGrowth::create(flat, p);
    REQUIRE(growth);
    REQUIRE(growth->update({{0, std::uint16_t(left)}, {4, std::uint16_t(right)}}));
    CHECK(growth->labels().at(2, 0, 0) == 4);
    CHECK(growth->labels().at(1, 0, 0) == left);
    CHECK(growth->labels().at(3, 0, 0) == right);
  }
}

TEST_CASE("Incremental updates (strokes added, erased, relabelled) equal a growth from scratch") {
  std::mt19937_64 rng(test::freshSeed("growth incremental"));
  const Dims dims{45, 38, 33};
  const Volume volume = randomVolume(rng, dims);
  GrowthParams params = randomParams(rng);
  CAPTURE(toString(params.weight));
  std::vector<GrowthSeed> seeds = randomSeeds(rng, dims, 4, 12);
  auto growth = LabelGrowth::create(volume, params);
  REQUIRE(growth);
  auto first = growth->update(seeds);
  REQUIRE(first);
  requireEqualToExact(*growth, volume, seeds, params);
  for (int step = 0; step < 6; ++step) {
    CAPTURE(step);
    std::vector<GrowthSeed> next = seeds;
    const int kind = step % 3;
    if (kind == 0) {  // a new stroke of an existing label
      std::vector<GrowthSeed> stroke = randomSeeds(rng, dims, 2, 1);
      for (GrowthSeed& s : stroke) s.label = seeds[0].label;
      for (const GrowthSeed& s : stroke)
        if (std::none_of(next.begin(), next.end(), [&](const GrowthSeed& o) { return o.index == s.index; })) next.push_back(s);
    } else if (kind == 1) {  // erase about a third of the seeds
      std::shuffle(next.begin(), next.end(), rng);
      next.resize(next.size() - next.size() / 3);
    } else {  // relabel a few seeds to a new label
      for (std::size_t i = 0; i < next.size(); i += 5) next[i].label = 41;
    }
    auto stats = growth->update(next);
    REQUIRE(stats);
    CHECK(stats->incremental);
    CHECK(stats->converged);
    requireEqualToExact(*growth, volume, next, params);
    seeds = next;
  }
  // Adding one voxel far from everything touches few bricks.
  std::vector<GrowthSeed> more = seeds;
  const std::size_t corner = dims.index(dims.x - 1, dims.y - 1, dims.z - 1);
  if (std::none_of(more.begin(), more.end(), [&](const GrowthSeed& s) { return s.index == corner; })) {
    more.push_back({corner, 40});
    auto stats = growth->update(more);
    REQUIRE(stats);
    CHECK(stats->voxelsReset == 0);
    CHECK(stats->brickVisits < first->brickVisits);
    requireEqualToExact(*growth, volume, more, params);
  }
}

TEST_CASE("Growth on the CPU gives the same bits with 1 or 2 threads and without AVX2") {
  std::mt19937_64 rng(test::freshSeed("growth threads"));
  const Dims dims{50, 41, 36};
  const Volume volume = randomVolume(rng, dims);
  const GrowthParams params = randomParams(rng);
  const std::vector<GrowthSeed> seeds = randomSeeds(rng, dims, 5, 20);
  for (const char* setting : {"threads=1", "threads=2", "no-avx2"}) {
    CAPTURE(setting);
    if (std::strcmp(setting, "no-avx2") == 0) setenv("AT_WDT_NO_AVX2", "1", 1);
    else setenv("AT_WDT_THREADS", setting + 8, 1);
    auto growth = LabelGrowth::create(volume, params);
    REQUIRE(growth);
    REQUIRE(growth->update(seeds));
    unsetenv("AT_WDT_THREADS");
    unsetenv("AT_WDT_NO_AVX2");
    requireEqualToExact(*growth, volume, seeds, params);
  }
}

TEST_CASE("A cancelled growth stops and the next update finishes it") {
  std::mt19937_64 rng(test::freshSeed("growth cancel"));
  const Dims dims{48, 48, 48};
  const Volume volume = randomVolume(rng, dims);
  const GrowthParams params = randomParams(rng);
  const std::vector<GrowthSeed> seeds = randomSeeds(rng, dims, 3, 6);
  auto growth = LabelGrowth::create(volume, params);
  REQUIRE(growth);
  std::atomic<bool> cancel{true};
  WdtControl control;
  control.cancel = &cancel;
  auto stats = growth->update(seeds, control);
  REQUIRE(stats);
  CHECK(stats->cancelled);
  CHECK(!stats->converged);
  CHECK(stats->brickVisits == 0);
  auto finished = growth->update(seeds);
  REQUIRE(finished);
  CHECK(finished->converged);
  requireEqualToExact(*growth, volume, seeds, params);
}

TEST_CASE("Growth errors: no seed, a seed off the grid, two labels on one voxel, a free step") {
  Geometry g;
  g.dims = {4, 4, 4};
  Volume v(g, 0);
  GrowthParams p;
  p.backend = WdtBackend::Cpu;
  auto growth = LabelGrowth::create(v, p);
  REQUIRE(growth);
  auto none = growth->update({});
  REQUIRE(!none);
  CHECK(none.error().message.find("no seed") != std::string::npos);
  auto outside = growth->update({{64, 1}, {0, 2}});
  REQUIRE(!outside);
  CHECK(outside.error().message.find("outside the 4x4x4 grid") != std::string::npos);
  auto twice = growth->update({{5, 1}, {5, 2}});
  REQUIRE(!twice);
  CHECK(twice.error().message.find("voxel (1,1,0) is seeded with two labels, 1 and 2") != std::string::npos);
  auto reserved = growth->update({{5, 65535}});
  REQUIRE(!reserved);
  // After the errors nothing was applied: the first real update grows from scratch.
  auto ok = growth->update({{0, 1}, {63, 2}});
  REQUIRE(ok);
  CHECK(!ok->incremental);
  p.baseCost = 0;
  auto free = LabelGrowth::create(v, p);
  REQUIRE(!free);
  CHECK(free.error().message.find("baseCost must be > 0") != std::string::npos);
  p.baseCost = 0.1f;
  p.windowMin = 5;
  p.windowMax = 5;
  CHECK(!LabelGrowth::create(v, p));
}

// A seed edit costs the region it changes: removing or relabelling seeds resets only the voxels
// that grew from them (on the CPU), not every voxel of their labels, and the result still equals
// the exact growth of the new seeds. Many small seeds of few labels, as a labelling of painted
// dabs; one random seed removed and one relabelled per step.
TEST_CASE("Removing or relabelling a seed resets only what grew from it, and equals the exact growth") {
  std::mt19937_64 rng(test::freshSeed("growth local reset"));
  const Dims dims{48, 40, 36};
  const Volume volume = randomVolume(rng, dims);
  GrowthParams params = randomParams(rng);
  CAPTURE(toString(params.weight));
  // 60 one-voxel seeds of 3 labels at distinct voxels.
  std::vector<GrowthSeed> seeds;
  std::set<std::size_t> taken;
  std::uniform_int_distribution<std::size_t> voxel(0, dims.count() - 1);
  const std::uint16_t labels[3] = {0, 7, 12};
  while (seeds.size() < 60) {
    const std::size_t v = voxel(rng);
    if (taken.insert(v).second) seeds.push_back({v, labels[seeds.size() % 3]});
  }
  auto growth = LabelGrowth::create(volume, params);
  REQUIRE(growth);
  REQUIRE(growth->update(seeds));
  for (int step = 0; step < 6; ++step) {
    CAPTURE(step);
    std::vector<GrowthSeed> next = seeds;
    std::uniform_int_distribution<std::size_t> pick(0, next.size() - 1);
    const std::size_t relabelled = pick(rng);
    const std::uint16_t oldLabel = next[relabelled].label;
    next[relabelled].label = labels[(std::find(labels, labels + 3, oldLabel) - labels + 1) % 3];
    std::size_t removed = pick(rng);
    if (removed == relabelled) removed = (removed + 1) % next.size();
    const std::uint16_t removedLabel = next[removed].label;
    next.erase(next.begin() + std::ptrdiff_t(removed));
    // The voxels a label-wide reset would take: every voxel of the two edited labels.
    std::size_t ofEditedLabels = 0;
    for (std::uint16_t l : growth->labels().voxels) ofEditedLabels += l == oldLabel || l == removedLabel;
    auto stats = growth->update(next);
    REQUIRE(stats);
    CHECK(stats->converged);
    CHECK(stats->voxelsReset >= 2);  // the edited seeds' own voxels at least
    CHECK(stats->voxelsReset < ofEditedLabels);
    MESSAGE("reset " << stats->voxelsReset << " voxels of " << ofEditedLabels << " in the edited labels");
    requireEqualToExact(*growth, volume, next, params);
    seeds = next;
  }
}
