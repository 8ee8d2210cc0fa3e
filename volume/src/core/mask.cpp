#include "volume/mask.h"

#include <algorithm>
#include <vector>

namespace at {

Mask structureMask(const LabelMap& labels, std::uint16_t label) {
  Mask mask(labels.geometry, 0);
  const std::size_t n = labels.voxels.size();
  for (std::size_t v = 0; v < n; ++v) mask.voxels[v] = labels.voxels[v] == label ? 1 : 0;
  return mask;
}

namespace {
template <class Grid, class Pred>
MaskStats measure(const Grid& grid, Pred inside) {
  MaskStats stats;
  const Dims& d = grid.geometry.dims;
  double sum[3] = {0, 0, 0};
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j) {
      std::size_t row = d.index(0, j, k);
      for (int i = 0; i < d.x; ++i) {
        if (!inside(grid.voxels[row + i])) continue;
        const int ijk[3] = {i, j, k};
        for (int a = 0; a < 3; ++a) {
          if (stats.voxelCount == 0 || ijk[a] < stats.box.min[a]) stats.box.min[a] = ijk[a];
          if (stats.voxelCount == 0 || ijk[a] > stats.box.max[a]) stats.box.max[a] = ijk[a];
          sum[a] += ijk[a];
        }
        ++stats.voxelCount;
      }
    }
  if (stats.voxelCount > 0) {
    const double n = double(stats.voxelCount);
    stats.centroidMm = grid.geometry.indexToPatient({sum[0] / n, sum[1] / n, sum[2] / n});
    stats.boxMinMm = grid.geometry.indexToPatient(
        {double(stats.box.min[0]), double(stats.box.min[1]), double(stats.box.min[2])});
    stats.boxMaxMm = grid.geometry.indexToPatient(
        {double(stats.box.max[0]), double(stats.box.max[1]), double(stats.box.max[2])});
  }
  return stats;
}
}  // namespace

MaskStats measureMask(const Mask& mask) {
  return measure(mask, [](std::uint8_t v) { return v != 0; });
}

MaskStats measureLabel(const LabelMap& labels, std::uint16_t label) {
  return measure(labels, [label](std::uint16_t v) { return v == label; });
}

int countComponents(const Mask& mask) {
  const Dims& d = mask.geometry.dims;
  std::vector<std::uint8_t> seen(mask.voxels.size(), 0);
  std::vector<std::size_t> stack;
  int components = 0;
  for (std::size_t start = 0; start < mask.voxels.size(); ++start) {
    if (!mask.voxels[start] || seen[start]) continue;
    ++components;
    seen[start] = 1;
    stack.push_back(start);
    while (!stack.empty()) {
      const std::size_t v = stack.back();
      stack.pop_back();
      const int i = int(v % d.x), j = int((v / d.x) % d.y), k = int(v / (std::size_t(d.x) * d.y));
      for (int dk = -1; dk <= 1; ++dk)
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            const int ni = i + di, nj = j + dj, nk = k + dk;
            if (!d.contains(ni, nj, nk)) continue;
            const std::size_t n = d.index(ni, nj, nk);
            if (mask.voxels[n] && !seen[n]) {
              seen[n] = 1;
              stack.push_back(n);
            }
          }
    }
  }
  return components;
}

}  // namespace at
