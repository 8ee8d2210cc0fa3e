// Splitting a structure into its pieces (LabelEditor::splitIslands): disjoint blobs become
// structures of their own by size, every voxel keeps a label of the original's family, the pieces
// are connected, bridges thinner than the minimum diameter are cut, specks below the minimum size
// stay, and one undo restores labels and structures.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>

#include "segment/label_editor.h"
#include "test_support.h"

using namespace at;
using namespace at::segment;

namespace {

Geometry grid() {
  Geometry g;
  g.dims = {48, 40, 32};
  g.spacingMm = {0.5, 0.5, 1.0};
  return g;
}

// Voxels within radius (mm) of centre (voxel coordinates) take `label`.
void ball(LabelMap& m, const std::array<double, 3>& c, double radiusMm, std::uint16_t label) {
  const Dims d = m.dims();
  const auto& s = m.geometry.spacingMm;
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const double x = (i - c[0]) * s[0], y = (j - c[1]) * s[1], z = (k - c[2]) * s[2];
        if (x * x + y * y + z * z <= radiusMm * radiusMm) m.voxels[d.index(i, j, k)] = label;
      }
}

// Whether the voxels of `label` are one 6-connected piece.
bool connected(const LabelMap& m, std::uint16_t label) {
  const Dims d = m.dims();
  std::vector<std::size_t> stack;
  std::vector<std::uint8_t> seen(m.voxels.size(), 0);
  std::size_t total = 0, reached = 0;
  for (std::size_t i = 0; i < m.voxels.size(); ++i)
    if (m.voxels[i] == label) {
      ++total;
      if (stack.empty() && !reached) stack.push_back(i), seen[i] = 1;
    }
  while (!stack.empty()) {
    const std::size_t v = stack.back();
    stack.pop_back();
    ++reached;
    const int x = int(v % std::size_t(d.x)), y = int(v / std::size_t(d.x) % std::size_t(d.y)),
              z = int(v / (std::size_t(d.x) * std::size_t(d.y)));
    const int next[6][3] = {{x - 1, y, z}, {x + 1, y, z}, {x, y - 1, z}, {x, y + 1, z}, {x, y, z - 1}, {x, y, z + 1}};
    for (const auto& n : next)
      if (d.contains(n[0], n[1], n[2])) {
        const std::size_t w = d.index(n[0], n[1], n[2]);
        if (m.voxels[w] == label && !seen[w]) seen[w] = 1, stack.push_back(w);
      }
  }
  return total > 0 && reached == total;
}

std::size_t count(const LabelMap& m, std::uint16_t label) {
  return std::size_t(std::count(m.voxels.begin(), m.voxels.end(), label));
}

}  // namespace

TEST_CASE("Split islands: separate blobs become structures by size, connected, voxels kept, one undo") {
  const std::uint64_t seed = test::freshSeed("split islands");
  INFO("seed " << seed);
  std::mt19937_64 random(seed);
  for (int round = 0; round < 5; ++round) {
    // 2 … 4 balls of label 3 in separate x slabs (gaps of 2+ voxels), another structure beside them.
    const int balls = 2 + int(random() % 3);
    LabelMap m(grid(), 0);
    std::uniform_real_distribution<double> radius(1.0, 2.5);
    for (int b = 0; b < balls; ++b) ball(m, {6.0 + 12.0 * b, 20.0, 16.0}, radius(random), 3);
    ball(m, {24.0, 34.0, 16.0}, 1.5, 7);
    Structure bone{};
    bone.label = 3, bone.id = "bone", bone.displayName = "Bone", bone.system = "skull bones";
    Structure other{};
    other.label = 7, other.id = "other", other.displayName = "Other";
    LabelEditor editor(m, {bone, other});
    const std::size_t total = count(m, 3), otherVoxels = count(m, 7);
    auto split = editor.splitIslands(3);
    REQUIRE_MESSAGE(split, split.error().message);
    CAPTURE(round);
    REQUIRE(split->newLabels.size() == std::size_t(balls - 1));
    const LabelMap& after = editor.labels();
    std::size_t sum = count(after, 3), previous = count(after, 3);
    CHECK(connected(after, 3));
    for (std::uint16_t l : split->newLabels) {
      CHECK(connected(after, l));
      CHECK(count(after, l) <= previous);  // by size: the original keeps the largest
      previous = count(after, l);
      sum += count(after, l);
      const auto s = std::find_if(editor.structures().begin(), editor.structures().end(),
                                  [&](const Structure& x) { return x.label == l; });
      REQUIRE(s != editor.structures().end());
      CHECK(s->displayName.rfind("Bone (", 0) == 0);
      CHECK(s->system == "skull bones");
    }
    CHECK(sum == total);
    CHECK(count(after, 7) == otherVoxels);
    REQUIRE(editor.undo());
    CHECK(editor.labels().voxels == m.voxels);
    CHECK(editor.structures().size() == 2);
  }
}

TEST_CASE("Split islands: a thin bridge is cut by the minimum diameter, specks stay, one piece is an error") {
  LabelMap m(grid(), 0);
  ball(m, {10, 20, 16}, 3.0, 3);
  ball(m, {38, 20, 16}, 3.0, 3);
  const Dims d = m.dims();
  for (int i = 10; i <= 38; ++i) m.voxels[d.index(i, 20, 16)] = 3;  // a one-voxel bridge
  m.voxels[d.index(2, 2, 2)] = 3;                                    // a speck
  Structure bone{};
  bone.label = 3, bone.id = "bone", bone.displayName = "Bone";
  {
    LabelEditor editor(m, {bone});
    // Without cutting: the two balls are one piece; the speck is the second, below 2 voxels.
    auto none = editor.splitIslands(3, 0, 2);
    REQUIRE_FALSE(none);
    CHECK(none.error().message.find("'Bone' has 2 piece(s)") != std::string::npos);
    CHECK(editor.history().size() == 0);
  }
  LabelEditor editor(m, {bone});
  auto split = editor.splitIslands(3, 2.0, 2);
  REQUIRE_MESSAGE(split, split.error().message);
  REQUIRE(split->newLabels.size() == 1);
  const LabelMap& after = editor.labels();
  const std::uint16_t piece = split->newLabels[0];
  // One ball each; the bridge's middle and the speck keep the original label.
  CHECK((after.voxels[d.index(10, 20, 16)] == 3) != (after.voxels[d.index(38, 20, 16)] == 3));
  CHECK((after.voxels[d.index(10, 20, 16)] == piece) != (after.voxels[d.index(38, 20, 16)] == piece));
  CHECK(after.voxels[d.index(24, 20, 16)] == 3);
  CHECK(after.voxels[d.index(2, 2, 2)] == 3);
  CHECK(connected(after, piece));
  CHECK(count(after, 3) + count(after, piece) == count(m, 3));
}
