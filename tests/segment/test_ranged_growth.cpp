// Grow from seeds with per-label value ranges (segment/ranged_growth.h, the seeds file's
// "grow_range"): ranged labels stay inside their range, unranged labels lose voxels only to them,
// and a bone plate's label no longer takes the soft tissue around it.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>

#include "segment/label_editor.h"
#include "segment/ranged_growth.h"
#include "segment/seeds.h"
#include "test_support.h"

using namespace at;
using namespace at::segment;

namespace {

Geometry cube(int n) {
  Geometry g;
  g.dims = {n, n, n};
  g.spacingMm = {1.0, 1.0, 1.5};
  return g;
}

LabelMap grow(const Volume& v, const std::vector<GrowthSeed>& seeds, const GrowthParams& p) {
  auto growth = LabelGrowth::create(v, p);
  REQUIRE(growth);
  REQUIRE(growth->update(seeds));
  return growth->labels();
}

GrowthParams cpuParams() {
  GrowthParams p;
  p.backend = WdtBackend::Cpu;
  p.baseCost = 0.02f;
  return p;
}

// Random boxes of air, soft tissue and bone over noise, on a 24³ grid; the last three boxes are one
// of each, so that every tissue's range holds some voxels.
Volume randomBoxes(std::mt19937_64& rng) {
  Volume v(cube(24), 0);
  std::uniform_int_distribution<int> at(0, 23), size(2, 9), kind(0, 2), noise(-40, 40);
  for (int b = 0; b < 40; ++b) {
    const int i0 = at(rng), j0 = at(rng), k0 = at(rng), s = size(rng);
    const int drawnKind = kind(rng);
    const std::int16_t value = std::array<std::int16_t, 3>{-900, 40, 900}[std::size_t(b >= 37 ? b - 37 : drawnKind)];
    for (int k = k0; k < std::min(24, k0 + s); ++k)
      for (int j = j0; j < std::min(24, j0 + s); ++j)
        for (int i = i0; i < std::min(24, i0 + s); ++i) v.at(i, j, k) = value;
  }
  for (auto& x : v.voxels) x = std::int16_t(x + noise(rng));
  return v;
}

// Up to `perLabel` seeds of each label 0 … 4 at random voxels of `v` (one label per voxel), sorted.
// A label of `ranges` gets its first seed inside its range (else all its seeds could fall outside
// it and it would grow nothing); randomBoxes puts voxels in every tissue's range.
std::vector<GrowthSeed> randomSeeds(std::mt19937_64& rng, const Volume& v, int perLabel,
                                    const std::vector<LabelValueRange>& ranges = {}) {
  std::vector<GrowthSeed> seeds;
  std::vector<char> used(v.voxels.size(), 0);
  std::uniform_int_distribution<std::size_t> voxel(0, v.voxels.size() - 1);
  for (std::uint16_t label = 0; label <= 4; ++label)
    for (int n = 0; n < perLabel; ++n) {
      std::size_t i = voxel(rng);
      const auto range = std::find_if(ranges.begin(), ranges.end(), [&](const LabelValueRange& r) { return r.label == label; });
      if (range != ranges.end() && n == 0)
        while (used[i] || v.voxels[i] < range->values[0] || v.voxels[i] > range->values[1]) i = voxel(rng);
      if (!used[i]) seeds.push_back({i, label}), used[i] = 1;
    }
  std::sort(seeds.begin(), seeds.end(), [](const GrowthSeed& a, const GrowthSeed& b) { return a.index < b.index; });
  return seeds;
}

}  // namespace

TEST_CASE("Ranged growth: ranged labels stay in range, unranged labels lose voxels only to a range holding them") {
  std::mt19937_64 rng(test::freshSeed("ranged growth"));
  const Volume v = randomBoxes(rng);
  const std::vector<LabelValueRange> ranges{{1, {300, 3000}}, {2, {300, 3000}}, {3, {-100, 200}}};
  const std::vector<GrowthSeed> seeds = randomSeeds(rng, v, 6, ranges);
  const auto rangeOf = [&](std::uint16_t l) -> const LabelValueRange* {
    for (const auto& r : ranges)
      if (r.label == l) return &r;
    return nullptr;
  };
  const GrowthParams p = cpuParams();
  const LabelMap plain = grow(v, seeds, p);
  auto ranged = growWithLabelRanges(v, IntensityModel{}, plain, seeds, p, ranges);
  REQUIRE_MESSAGE(ranged, (ranged ? "" : ranged.error().message));
  std::size_t inRanged = 0;
  for (std::size_t i = 0; i < v.voxels.size(); ++i) {
    const std::uint16_t now = ranged->voxels[i], before = plain.voxels[i];
    if (const LabelValueRange* r = rangeOf(now)) {
      ++inRanged;
      CHECK(v.voxels[i] >= r->values[0]);
      CHECK(v.voxels[i] <= r->values[1]);
    } else if (now != 0) {
      CHECK(now == before);  // an unranged label never gains
    }
    if (before != now && before != 0 && !rangeOf(before)) {
      REQUIRE(rangeOf(now));  // an unranged label loses a voxel only to a range that holds it
    }
  }
  CHECK(inRanged > 0);
  // No ranges: the plain growth, with nothing changed.
  auto none = growWithLabelRanges(v, IntensityModel{}, plain, seeds, p, {});
  REQUIRE(none);
  CHECK(none->voxels == plain.voxels);
  // Errors name the problem.
  auto background = growWithLabelRanges(v, IntensityModel{}, plain, seeds, p, {{0, {300, 3000}}});
  REQUIRE(!background);
  CHECK(background.error().message.find("background") != std::string::npos);
  auto inverted = growWithLabelRanges(v, IntensityModel{}, plain, seeds, p, {{1, {3000, 300}}});
  REQUIRE(!inverted);
  CHECK(inverted.error().message.find("not low < high") != std::string::npos);
}

TEST_CASE("Ranged growth: a hollow bone's label is its cortex, not the soft marrow it encloses") {
  const Geometry g = cube(32);
  Volume v(g, 40);  // soft tissue
  // A hollow bar: cortical walls two voxels thick around soft marrow at i 14-17, j 6-25.
  for (int k = 0; k < 32; ++k)
    for (int j = 4; j < 28; ++j)
      for (int i = 12; i < 20; ++i)
        if (i < 14 || i > 17 || j < 6 || j > 25) v.at(i, j, k) = 1200;
  std::vector<GrowthSeed> seeds;
  // The bone's seeds are on its wall; the background's are out in the soft tissue on both sides.
  for (int k = 4; k < 28; k += 6) seeds.push_back({g.dims.index(12, 16, k), 1});
  for (int k = 2; k < 32; k += 10) {
    seeds.push_back({g.dims.index(1, 16, k), 0});
    seeds.push_back({g.dims.index(30, 16, k), 0});
  }
  std::sort(seeds.begin(), seeds.end(), [](const GrowthSeed& a, const GrowthSeed& b) { return a.index < b.index; });
  const GrowthParams p = cpuParams();
  const LabelMap plain = grow(v, seeds, p);
  std::size_t plainSoft = 0;
  for (std::size_t i = 0; i < v.voxels.size(); ++i) plainSoft += plain.voxels[i] == 1 && v.voxels[i] < 300;
  REQUIRE(plainSoft > 100);  // the precondition: unranged, the bone's label takes its marrow
  auto ranged = growWithLabelRanges(v, IntensityModel{}, plain, seeds, p, {{1, {300, 3000}}});
  REQUIRE(ranged);
  std::size_t plate = 0, label = 0;
  for (std::size_t i = 0; i < v.voxels.size(); ++i) {
    plate += v.voxels[i] >= 300;
    label += ranged->voxels[i] == 1;
    if (ranged->voxels[i] == 1) CHECK(v.voxels[i] >= 300);
  }
  CHECK(label == plate);  // the whole cortex (one connected piece with seeds, no rival in it)
}

TEST_CASE("A label's grow_range in the seeds file: a range or \"bone\", written back, errors naming the field") {
  const std::string head = R"({"labels": [{"value": 0, "name": "background"}, )";
  const std::string tail = R"(], "strokes": [{"label": 0, "points": [[0, 0, 0]]}]})";
  auto seeds = parseSeeds(head + R"({"value": 2, "name": "mandible", "grow_range": "bone"}, {"value": 3, "name": "arch", "grow_range": [200, 4000]}, {"value": 4, "name": "sinus"})" + tail, "s.json");
  REQUIRE_MESSAGE(seeds, (seeds ? "" : seeds.error().message));
  CHECK(seeds->labels[1].growRangeBone);
  CHECK(seeds->labels[2].growRange == std::array<double, 2>{200, 4000});
  CHECK(!seeds->labels[3].hasGrowRange());
  const auto ranges = labelRangesOf(*seeds, {150, 32767});
  REQUIRE(ranges.size() == 2);
  CHECK(ranges[0].label == 2);
  CHECK(ranges[0].values == std::array<double, 2>{150, 32767});
  CHECK(ranges[1].values == std::array<double, 2>{200, 4000});
  auto again = parseSeeds(seedsToJson(*seeds), "again.json");
  REQUIRE(again);
  CHECK(again->labels[1].growRangeBone);
  CHECK(again->labels[2].growRange == seeds->labels[2].growRange);
  for (const auto& [bad, mention] : std::vector<std::pair<std::string, std::string>>{
           {R"({"value": 2, "name": "m", "grow_range": "soft"})", "labels[1].grow_range"},
           {R"({"value": 2, "name": "m", "grow_range": [400, 300]})", "labels[1].grow_range"},
       }) {
    auto r = parseSeeds(head + bad + tail, "s.json");
    REQUIRE(!r);
    CAPTURE(r.error().message);
    CHECK(r.error().message.find(mention) != std::string::npos);
  }
  auto bg = parseSeeds(R"({"labels": [{"value": 0, "name": "background", "grow_range": "bone"}, {"value": 1, "name": "x"}], "strokes": []})", "s.json");
  REQUIRE(!bg);
  CHECK(bg.error().message.find("labels[0].grow_range") != std::string::npos);
}

TEST_CASE("Ranged growth kept between seed edits (the segment editor's live growth) equals a fresh one every time") {
  std::mt19937_64 rng(test::freshSeed("ranged growth kept"));
  const Volume v = randomBoxes(rng);
  const GrowthParams p = cpuParams();
  const std::vector<LabelValueRange> ranges{{1, {300, 3000}}, {2, {-100, 200}}, {3, {300, 3000}}};
  LabelEditor editor(LabelMap(v.geometry, 0), {});
  std::vector<GrowthSeed> seeds = randomSeeds(rng, v, 5, ranges);
  for (int round = 0; round < 4; ++round) {
    CAPTURE(round);
    // What the command line computes from scratch: the ordinary growth, then the rule.
    auto fresh = growWithLabelRanges(v, IntensityModel{}, grow(v, seeds, p), seeds, p, ranges);
    REQUIRE(fresh);
    GrowthStats stats;
    auto edited = editor.growFromSeeds(v, seeds, p, &stats, LabelRanges{IntensityModel{}, ranges});
    REQUIRE_MESSAGE(edited, (edited ? "" : edited.error().message));
    CHECK(editor.labels().voxels == fresh->voxels);
    CHECK(stats.incremental == (round > 0));
    // The user's next edit: some seeds removed, some relabelled, some added.
    std::vector<GrowthSeed> next;
    std::uniform_int_distribution<int> fate(0, 5);
    std::uniform_int_distribution<int> label(0, 4);
    for (GrowthSeed s : seeds) {
      const int f = fate(rng);
      if (f == 0) continue;
      if (f == 1) s.label = std::uint16_t(label(rng));
      next.push_back(s);
    }
    for (const GrowthSeed& s : randomSeeds(rng, v, 2))
      if (std::none_of(next.begin(), next.end(), [&](const GrowthSeed& o) { return o.index == s.index; })) next.push_back(s);
    std::sort(next.begin(), next.end(), [](const GrowthSeed& a, const GrowthSeed& b) { return a.index < b.index; });
    seeds = std::move(next);
  }
  // Without ranges the editor's labels are the ordinary growth's again.
  REQUIRE(editor.growFromSeeds(v, seeds, p));
  CHECK(editor.labels().voxels == grow(v, seeds, p).voxels);
}
