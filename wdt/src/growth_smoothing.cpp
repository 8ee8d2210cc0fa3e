// Smoothing of a growth's values (growth_smoothing.h).
#include "growth_smoothing.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "core/parallel_rows.h"

namespace at::wdt {

std::vector<float> gaussianSmoothed(const Volume& volume, float sigmaVoxels) {
  const Dims d = volume.dims();
  std::vector<float> a(volume.voxels.begin(), volume.voxels.end()), b(a.size());
  const int radius = std::max(1, int(std::ceil(2.5f * sigmaVoxels)));
  std::vector<float> taps(std::size_t(2 * radius + 1));
  float sum = 0;
  for (int t = -radius; t <= radius; ++t)
    sum += taps[std::size_t(t + radius)] = std::exp(-0.5f * float(t * t) / (sigmaVoxels * sigmaVoxels));
  for (float& t : taps) t /= sum;
  const int n[3] = {d.x, d.y, d.z};
  const std::size_t stride[3] = {1, std::size_t(d.x), std::size_t(d.x) * std::size_t(d.y)};
  for (int axis = 0; axis < 3; ++axis) {
    const int len = n[axis];
    if (len < 2) continue;
    for (std::size_t v = 0; v < a.size(); ++v) {
      const int along = int(v / stride[axis] % std::size_t(len));
      const std::size_t start = v - std::size_t(along) * stride[axis];
      float acc = 0;
      for (int t = -radius; t <= radius; ++t) {
        const int at = std::clamp(along + t, 0, len - 1);
        acc += taps[std::size_t(t + radius)] * a[start + std::size_t(at) * stride[axis]];
      }
      b[v] = acc;
    }
    std::swap(a, b);
  }
  return a;
}

std::vector<float> edgePreservingSmoothed(const Volume& volume, float sigmaVoxels, float edgeSigma) {
  const Dims d = volume.dims();
  const int radius = std::clamp(int(std::ceil(2.0f * sigmaVoxels)), 1, 3);
  struct Tap {
    int di, dj, dk;
    float weight;
  };
  std::vector<Tap> taps;
  for (int dk = -radius; dk <= radius; ++dk)
    for (int dj = -radius; dj <= radius; ++dj)
      for (int di = -radius; di <= radius; ++di) {
        const int r2 = di * di + dj * dj + dk * dk;
        if (r2 > radius * radius) continue;
        taps.push_back({di, dj, dk, std::exp(-0.5f * float(r2) / (sigmaVoxels * sigmaVoxels))});
      }
  // Range weights by integer difference of stored values, out to where they vanish (4 edgeSigma).
  const int reach = std::max(1, int(std::ceil(4.0f * edgeSigma)));
  std::vector<float> range(std::size_t(reach) + 1);
  for (int t = 0; t <= reach; ++t) range[std::size_t(t)] = std::exp(-0.5f * float(t * t) / (edgeSigma * edgeSigma));
  // Each tap's index offset, for voxels whose whole neighbourhood lies inside the grid (no bounds
  // checks there); the taps are summed in the same order either way, so both paths round alike.
  std::vector<std::ptrdiff_t> offsets;
  for (const Tap& t : taps) offsets.push_back(std::ptrdiff_t(t.di) + std::ptrdiff_t(d.x) * (t.dj + std::ptrdiff_t(d.y) * t.dk));
  std::vector<float> out(volume.voxels.size());
  const std::int16_t* voxels = volume.voxels.data();
  const auto slab = [&](int k0, int k1) {
    for (int k = k0; k < k1; ++k)
      for (int j = 0; j < d.y; ++j) {
        const bool innerRow = k >= radius && k + radius < d.z && j >= radius && j + radius < d.y;
        for (int i = 0; i < d.x; ++i) {
          const std::size_t v = d.index(i, j, k);
          const int centre = voxels[v];
          float sum = 0, weight = 0;
          if (innerRow && i >= radius && i + radius < d.x) {
            for (std::size_t t = 0; t < taps.size(); ++t) {
              const int value = voxels[std::ptrdiff_t(v) + offsets[t]];
              const int diff = std::abs(value - centre);
              if (diff > reach) continue;
              const float w = taps[t].weight * range[std::size_t(diff)];
              sum += w * float(value);
              weight += w;
            }
          } else {
            for (const Tap& t : taps) {
              const int x = i + t.di, y = j + t.dj, z = k + t.dk;
              if (x < 0 || y < 0 || z < 0 || x >= d.x || y >= d.y || z >= d.z) continue;
              const int value = voxels[d.index(x, y, z)];
              const int diff = std::abs(value - centre);
              if (diff > reach) continue;
              const float w = t.weight * range[std::size_t(diff)];
              sum += w * float(value);
              weight += w;
            }
          }
          out[v] = sum / weight;  // the centre's own tap has weight 1
        }
      }
  };
  forEachBlockInParallel(d.z, slab, 16);
  return out;
}

}  // namespace at::wdt
