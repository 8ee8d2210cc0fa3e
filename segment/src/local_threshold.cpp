// A local threshold (local_threshold.h).
#include "segment/local_threshold.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace at::segment {

Result<std::vector<std::size_t>> localThresholdRegion(const Volume& volume, const IntensityModel& intensity,
                                                      const std::array<int, 3>& centre, double radiusMm, double low,
                                                      double high) {
  const Geometry& g = volume.geometry;
  const Dims d = g.dims;
  if (!d.contains(centre[0], centre[1], centre[2]))
    return fail("local threshold: voxel (" + std::to_string(centre[0]) + ", " + std::to_string(centre[1]) + ", " +
                std::to_string(centre[2]) + ") is outside the volume (" + d.toString() + ")");
  if (!(radiusMm >= 0)) return fail("local threshold: the radius must be >= 0 mm");
  if (!(low <= high)) return fail("local threshold: the range needs low <= high");
  const auto inRange = [&](std::size_t v) {
    const double value = intensity.valueOf(volume.voxels[v]);
    return value >= low && value <= high;
  };
  const std::size_t start = d.index(centre[0], centre[1], centre[2]);
  if (!inRange(start)) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "local threshold: the value under the voxel (%g %s) is outside %g … %g",
                  intensity.valueOf(volume.voxels[start]), intensity.unitName(), low, high);
    return fail(buf);
  }
  // A flood fill within the ball's box; `taken` is indexed in the box.
  int lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const int reach = int(std::floor(radiusMm / g.spacingMm[std::size_t(a)] + 1e-9));
    const int n = a == 0 ? d.x : a == 1 ? d.y : d.z;
    lo[a] = std::max(0, centre[std::size_t(a)] - reach);
    hi[a] = std::min(n - 1, centre[std::size_t(a)] + reach);
  }
  const int bx = hi[0] - lo[0] + 1, by = hi[1] - lo[1] + 1, bz = hi[2] - lo[2] + 1;
  std::vector<std::uint8_t> taken(std::size_t(bx) * std::size_t(by) * std::size_t(bz), 0);
  const auto inBall = [&](int i, int j, int k) {
    const double dx = (i - centre[0]) * g.spacingMm[0], dy = (j - centre[1]) * g.spacingMm[1],
                 dz = (k - centre[2]) * g.spacingMm[2];
    return dx * dx + dy * dy + dz * dz <= radiusMm * radiusMm + 1e-9;
  };
  const auto boxIndex = [&](int i, int j, int k) {
    return std::size_t(i - lo[0]) + std::size_t(bx) * (std::size_t(j - lo[1]) + std::size_t(by) * std::size_t(k - lo[2]));
  };
  std::vector<std::array<int, 3>> stack{centre};
  taken[boxIndex(centre[0], centre[1], centre[2])] = 1;
  std::vector<std::size_t> out;
  const int steps[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  while (!stack.empty()) {
    const std::array<int, 3> p = stack.back();
    stack.pop_back();
    out.push_back(d.index(p[0], p[1], p[2]));
    for (const auto& s : steps) {
      const int i = p[0] + s[0], j = p[1] + s[1], k = p[2] + s[2];
      if (i < lo[0] || j < lo[1] || k < lo[2] || i > hi[0] || j > hi[1] || k > hi[2]) continue;
      std::uint8_t& t = taken[boxIndex(i, j, k)];
      if (t || !inBall(i, j, k) || !inRange(d.index(i, j, k))) continue;
      t = 1;
      stack.push_back({i, j, k});
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace at::segment
