// The local threshold (segment/local_threshold.h): on random volumes with anisotropic spacing,
// its region equals a brute-force one (every in-ball, in-range voxel joined to the centre by a
// breadth-first search over the whole grid restricted to the ball); it never holds a voxel out of
// range or outside the ball; and it works from any value — the background's air as well as bone.
#include <doctest/doctest.h>

#include <cstdio>
#include <deque>
#include <random>

#include "segment/local_threshold.h"
#include "test_support.h"

using namespace at;

namespace {

// Brute force: a breadth-first search from the centre over voxels inside the ball and in range.
std::vector<std::size_t> reference(const Volume& vol, const std::array<int, 3>& c, double r, double low, double high) {
  const Dims d = vol.geometry.dims;
  const auto ok = [&](int i, int j, int k) {
    if (!d.contains(i, j, k)) return false;
    const double dx = (i - c[0]) * vol.geometry.spacingMm[0], dy = (j - c[1]) * vol.geometry.spacingMm[1],
                 dz = (k - c[2]) * vol.geometry.spacingMm[2];
    const double v = vol.voxels[d.index(i, j, k)];
    return dx * dx + dy * dy + dz * dz <= r * r + 1e-9 && v >= low && v <= high;
  };
  std::vector<std::uint8_t> seen(vol.voxels.size(), 0);
  std::vector<std::size_t> out;
  std::deque<std::array<int, 3>> queue{c};
  seen[d.index(c[0], c[1], c[2])] = 1;
  while (!queue.empty()) {
    const auto p = queue.front();
    queue.pop_front();
    out.push_back(d.index(p[0], p[1], p[2]));
    const int steps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& s : steps) {
      const int i = p[0] + s[0], j = p[1] + s[1], k = p[2] + s[2];
      if (!ok(i, j, k) || seen[d.index(i, j, k)]) continue;
      seen[d.index(i, j, k)] = 1;
      queue.push_back({i, j, k});
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST_CASE("A local threshold takes the in-range voxels joined to the click inside the ball, from air or bone") {
  const std::uint64_t seed = test::freshSeed("local threshold volumes");
  std::mt19937_64 random(seed);
  IntensityModel hu;  // CT: stored values are HU
  for (int trial = 0; trial < 40; ++trial) {
    Geometry g;
    g.dims = {int(random() % 20) + 5, int(random() % 20) + 5, int(random() % 12) + 3};
    g.spacingMm = {0.1 + double(random() % 10) / 10.0, 0.1 + double(random() % 10) / 10.0, 0.2 + double(random() % 30) / 10.0};
    Volume vol(g, 0);
    // Air (−1000) with bone (1200) in random blobs and soft tissue (40) elsewhere.
    std::uniform_int_distribution<int> kind(0, 2);
    for (auto& v : vol.voxels) v = std::int16_t(std::array<int, 3>{-1000, 40, 1200}[std::size_t(kind(random))]);
    const std::array<int, 3> c = {int(random() % std::uint64_t(g.dims.x)), int(random() % std::uint64_t(g.dims.y)),
                                  int(random() % std::uint64_t(g.dims.z))};
    // The range of the clicked voxel's own class: air for the background, bone for a bone's seeds.
    const double here = vol.voxels[g.dims.index(c[0], c[1], c[2])];
    const double low = here - 100, high = here + 100;
    const double r = double(random() % 40) / 10.0;
    CAPTURE(trial);
    auto region = segment::localThresholdRegion(vol, hu, c, r, low, high);
    REQUIRE(region);
    CHECK(*region == reference(vol, c, r, low, high));
    CHECK(std::find(region->begin(), region->end(), g.dims.index(c[0], c[1], c[2])) != region->end());
    for (std::size_t v : *region) CHECK((vol.voxels[v] >= low && vol.voxels[v] <= high));
    // Out of range under the click: refused, naming the value.
    auto refused = segment::localThresholdRegion(vol, hu, c, r, here + 1, here + 2);
    REQUIRE_FALSE(refused);
    CHECK(refused.error().message.find("is outside") != std::string::npos);
  }
  Geometry g;
  g.dims = {4, 4, 4};
  Volume vol(g, 0);
  CHECK_FALSE(segment::localThresholdRegion(vol, hu, {4, 0, 0}, 1, -10, 10));
  CHECK_FALSE(segment::localThresholdRegion(vol, hu, {0, 0, 0}, -1, -10, 10));
  CHECK_FALSE(segment::localThresholdRegion(vol, hu, {0, 0, 0}, 1, 10, -10));
}
