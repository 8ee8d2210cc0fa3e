// Trilinear sampling of a (possibly downsampled) distance field at the voxel centres of another
// grid in the same patient frame: what upsampleField does for every voxel and upsampledValueAt
// for one, written once so that both give the same value bit for bit.
#pragma once

#include <algorithm>
#include <cmath>

#include "volume/grid.h"

namespace at::wdt::detail {

// index_source = A · index_target + b: the affine map evaluated once (origin and the three axis steps).
struct GridMap {
  Vec3 b{0, 0, 0};
  Vec3 cols[3];
  GridMap(const Geometry& source, const Geometry& target) {
    b = source.patientToIndex(target.indexToPatient({0, 0, 0}));
    for (int a = 0; a < 3; ++a) {
      Vec3 e{0, 0, 0};
      e[a] = 1;
      cols[a] = source.patientToIndex(target.indexToPatient(e)) - b;
    }
  }
};

// The value at target voxel (i, j, k): trilinear over the 8 source voxels around it (clamped to
// the source grid); where one of them is unreachable (+inf), the nearest of the 8 instead.
// `src` must not be empty.
inline float sampleMapped(const FloatVolume& src, const GridMap& m, int i, int j, int k) {
  const Dims sd = src.geometry.dims;
  const int n[3] = {sd.x, sd.y, sd.z};
  int i0[3], i1[3];
  double t[3];
  for (int a = 0; a < 3; ++a) {
    double p = m.b[a] + m.cols[0][a] * i + m.cols[1][a] * j + m.cols[2][a] * k;
    p = std::clamp(p, 0.0, double(n[a] - 1));
    i0[a] = std::min(int(p), n[a] - 1);
    i1[a] = std::min(i0[a] + 1, n[a] - 1);
    t[a] = p - i0[a];
  }
  double acc = 0;
  for (int c = 0; c < 8; ++c) {
    const int cx = c & 1 ? i1[0] : i0[0], cy = c & 2 ? i1[1] : i0[1], cz = c & 4 ? i1[2] : i0[2];
    const float v = src.voxels[sd.index(cx, cy, cz)];
    if (!std::isfinite(v))
      return src.voxels[sd.index(t[0] < 0.5 ? i0[0] : i1[0], t[1] < 0.5 ? i0[1] : i1[1], t[2] < 0.5 ? i0[2] : i1[2])];
    acc += (c & 1 ? t[0] : 1 - t[0]) * (c & 2 ? t[1] : 1 - t[1]) * (c & 4 ? t[2] : 1 - t[2]) * v;
  }
  return float(acc);
}

}  // namespace at::wdt::detail
