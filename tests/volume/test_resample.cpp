// Nearest-neighbour label resampling through both patient frames.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "io_test_files.h"
#include "test_support.h"
#include "volume/image_file.h"
#include "volume/nifti_io.h"
#include "volume/resample.h"

using namespace at;
using namespace at::test;

namespace {

LabelMap randomLabels(std::mt19937_64& rng, const Geometry& g) {
  LabelMap labels(g);
  std::uniform_int_distribution<int> value(0, 300);
  for (auto& v : labels.voxels) v = std::uint16_t(value(rng));
  return labels;
}

// The same voxel centres as `g`, indexed with axes permuted by `perm` and flipped where `flip`:
// target axis a walks source axis perm[a], backwards if flip[a].
Geometry reindexed(const Geometry& g, const int perm[3], const bool flip[3]) {
  Geometry t;
  const int sizes[3] = {g.dims.x, g.dims.y, g.dims.z};
  t.dims = {sizes[perm[0]], sizes[perm[1]], sizes[perm[2]]};
  Vec3 startIndex{0, 0, 0};
  for (int a = 0; a < 3; ++a) {
    const int s = perm[a];
    t.spacingMm[std::size_t(a)] = g.spacingMm[std::size_t(s)];
    const Vec3 column = g.direction.column(s);
    for (int r = 0; r < 3; ++r) t.direction.m[std::size_t(r)][std::size_t(a)] = flip[a] ? -column[std::size_t(r)] : column[std::size_t(r)];
    if (flip[a]) startIndex[std::size_t(s)] = sizes[s] - 1;
  }
  t.originMm = g.indexToPatient(startIndex);
  return t;
}

}  // namespace

TEST_CASE("a label map resampled onto a flipped and permuted grid and back is identical") {
  std::mt19937_64 rng(freshSeed("resample flip/permute"));
  const Geometry g = randomObliqueGeometry(rng, {9, 7, 5});
  const LabelMap labels = randomLabels(rng, g);
  const int perms[][3] = {{0, 1, 2}, {2, 0, 1}, {1, 2, 0}, {2, 1, 0}};
  for (const auto& perm : perms)
    for (int flips = 0; flips < 8; ++flips) {
      const bool flip[3] = {bool(flips & 1), bool(flips & 2), bool(flips & 4)};
      const Geometry t = reindexed(g, perm, flip);
      auto there = resampleLabelsNearest(labels, t);
      REQUIRE_MESSAGE(there, there.error().message);
      // Spot check: the target voxel's source is the reindexed voxel.
      const int sizes[3] = {g.dims.x, g.dims.y, g.dims.z};
      int src[3];
      const int tIndex[3] = {1, 2, 3};
      for (int a = 0; a < 3; ++a) src[perm[a]] = flip[a] ? sizes[perm[a]] - 1 - tIndex[a] : tIndex[a];
      if (t.dims.contains(1, 2, 3)) CHECK(there->at(1, 2, 3) == labels.at(src[0], src[1], src[2]));
      auto back = resampleLabelsNearest(*there, g);
      REQUIRE(back);
      CHECK(back->voxels == labels.voxels);
    }
}

TEST_CASE("a grid shifted by whole voxels keeps the overlap and fills the rest with 0") {
  std::mt19937_64 rng(freshSeed("resample shift"));
  const Geometry g = randomObliqueGeometry(rng, {8, 6, 4});
  const LabelMap labels = randomLabels(rng, g);
  Geometry shifted = g;
  shifted.originMm = g.indexToPatient({3, -2, 1});
  auto there = resampleLabelsNearest(labels, shifted);
  REQUIRE(there);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 8; ++i) {
        const int si = i + 3, sj = j - 2, sk = k + 1;
        const std::uint16_t expected = g.dims.contains(si, sj, sk) ? labels.at(si, sj, sk) : 0;
        CHECK(there->at(i, j, k) == expected);
      }
  auto back = resampleLabelsNearest(*there, g);
  REQUIRE(back);
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 6; ++j)
      for (int i = 0; i < 8; ++i) {
        const bool kept = shifted.dims.contains(i - 3, j + 2, k - 1);
        CHECK(back->at(i, j, k) == (kept ? labels.at(i, j, k) : 0));
      }
}

TEST_CASE("an oblique target voxel takes the label of the hand-computed nearest source voxel") {
  // Source: axis-aligned LPS, 1 mm, origin 0; label = 1 + i + 10 j + 100 k.
  Geometry s;
  s.dims = {10, 10, 10};
  LabelMap source(s);
  for (int k = 0; k < 10; ++k)
    for (int j = 0; j < 10; ++j)
      for (int i = 0; i < 10; ++i) source.at(i, j, k) = std::uint16_t(1 + i + 10 * j + 100 * k);
  // Target: rotated 30° about z, spacing (2, 2, 1.5), origin (2, 3, 1).
  Geometry t;
  t.dims = {4, 4, 4};
  const double c = std::cos(M_PI / 6), sn = std::sin(M_PI / 6);
  t.direction.m = {{{c, -sn, 0}, {sn, c, 0}, {0, 0, 1}}};
  t.spacingMm = {2, 2, 1.5};
  t.originMm = {2, 3, 1};
  auto out = resampleLabelsNearest(source, t);
  REQUIRE(out);
  // Voxel (3,1,2): (2,3,1) + 3·2·(0.866,0.5,0) + 1·2·(−0.5,0.866,0) + 2·1.5·(0,0,1) = (6.196, 7.732, 4.0)
  // → nearest source voxel (6, 8, 4) → label 1 + 6 + 80 + 400.
  CHECK(out->at(3, 1, 2) == 487);
  // Voxel (0,3,0): (2,3,1) + 3·2·(−0.5,0.866,0) = (−1, 8.196, 1) → outside the source → 0.
  CHECK(out->at(0, 3, 0) == 0);
}

TEST_CASE("grids that do not overlap are an error, not an empty label map") {
  Geometry s;
  s.dims = {4, 4, 4};
  const LabelMap source(s, 1);
  Geometry t = s;
  t.originMm = {100, 0, 0};
  auto out = resampleLabelsNearest(source, t);
  REQUIRE_FALSE(out);
  CHECK(out.error().message.find("does not overlap") != std::string::npos);
}

TEST_CASE("seg_small resampled onto the CT grid (the same grid) is unchanged, and back through a flip too") {
  if (!requireSharedData("seg_small.nii.gz")) return;
  const std::string segPath = sharedData("totalsegmentator/seg_small.nii.gz").string();
  auto seg = loadNifti(segPath);
  REQUIRE(seg);
  auto labels = toLabelMap(*seg, segPath);
  REQUIRE(labels);
  auto same = resampleLabelsNearest(*labels, labels->geometry);
  REQUIRE(same);
  CHECK(same->voxels == labels->voxels);
  const int perm[3] = {1, 0, 2};
  const bool flip[3] = {true, false, true};
  auto flipped = resampleLabelsNearest(*labels, reindexed(labels->geometry, perm, flip));
  REQUIRE(flipped);
  auto back = resampleLabelsNearest(*flipped, labels->geometry);
  REQUIRE(back);
  CHECK(back->voxels == labels->voxels);
}

// labelsLostInResampling names exactly the source labels no resampled voxel carries, with their
// source voxel counts, for random maps resampled onto coarser, shifted grids.
TEST_CASE("resampling: the labels lost are exactly those the resampled map lacks") {
  std::mt19937_64 rng(test::freshSeed("labels lost in resampling"));
  for (int trial = 0; trial < 20; ++trial) {
    Geometry fine;
    fine.dims = {24, 20, 16};
    fine.spacingMm = {0.5, 0.5, 0.5};
    LabelMap source(fine, 0);
    // A few labels of 1 … 40 voxels scattered over the grid, on top of one large label.
    std::uniform_int_distribution<int> x(0, 23), y(0, 19), z(0, 15), size(1, 40);
    for (auto& v : source.voxels) v = 1;
    for (std::uint16_t label = 2; label < 12; ++label)
      for (int n = size(rng); n > 0; --n) source.at(x(rng), y(rng), z(rng)) = label;
    Geometry coarse;
    coarse.dims = {5, 4, 3};
    coarse.spacingMm = {2.5, 2.5, 2.5};
    std::uniform_real_distribution<double> shift(-2.0, 2.0);
    coarse.originMm = {shift(rng), shift(rng), shift(rng)};
    auto resampled = resampleLabelsNearest(source, coarse);
    REQUIRE(resampled);
    std::vector<std::size_t> before(65536, 0), after(65536, 0);
    for (auto v : source.voxels) ++before[v];
    for (auto v : resampled->voxels) ++after[v];
    const std::vector<LostLabel> lost = labelsLostInResampling(source, *resampled);
    std::size_t expected = 0;
    for (std::size_t label = 1; label < 65536; ++label) {
      if (!before[label] || after[label]) continue;
      ++expected;
      auto it = std::find_if(lost.begin(), lost.end(), [&](const LostLabel& l) { return l.label == label; });
      REQUIRE(it != lost.end());
      CHECK(it->sourceVoxels == before[label]);
    }
    CHECK(lost.size() == expected);
    CHECK(std::is_sorted(lost.begin(), lost.end(), [](const LostLabel& a, const LostLabel& b) { return a.label < b.label; }));
  }
}
