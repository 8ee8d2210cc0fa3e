// Exact Euclidean distance transform in mm (Felzenszwalb & Huttenlocher: per axis, the lower
// envelope of the parabolas (x − q·s)² + f(q)), and the ball morphology built on it.
#include "segment/distance_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/parallel_rows.h"

namespace at::segment {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Squared distances along one line of n values (stride `stride` in `data`) with spacing s: each
// becomes min over q of ((p − q)·s)² + f(q). Scratch arrays are the caller's.
void transformLine(double* data, std::size_t stride, int n, double s, std::vector<double>& f, std::vector<int>& v,
                   std::vector<double>& z) {
  f.resize(std::size_t(n));
  v.resize(std::size_t(n));
  z.resize(std::size_t(n) + 1);
  for (int q = 0; q < n; ++q) f[std::size_t(q)] = data[std::size_t(q) * stride];
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (!(f[std::size_t(q)] < kInf)) continue;
    const double fq = f[std::size_t(q)] + (q * s) * (q * s);
    double cross = -kInf;
    while (k >= 0) {
      const int r = v[std::size_t(k)];
      cross = (fq - (f[std::size_t(r)] + (r * s) * (r * s))) / (2 * s * (q - r));
      if (cross > z[std::size_t(k)]) break;
      --k;
    }
    ++k;
    v[std::size_t(k)] = q;
    z[std::size_t(k)] = k == 0 ? -kInf : cross;
    z[std::size_t(k) + 1] = kInf;
  }
  if (k < 0) return;  // no finite value: the line stays +infinity
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[std::size_t(j) + 1] < q * s) ++j;
    const int r = v[std::size_t(j)];
    data[std::size_t(q) * stride] = ((q - r) * s) * ((q - r) * s) + f[std::size_t(r)];
  }
}

}  // namespace

FloatVolume distanceToMask(const Mask& mask) {
  const Geometry& g = mask.geometry;
  const Dims d = g.dims;
  std::vector<double> sq(d.count());
  for (std::size_t i = 0; i < sq.size(); ++i) sq[i] = mask.voxels[i] ? 0.0 : kInf;
  const std::size_t nx = std::size_t(d.x), nxy = nx * std::size_t(d.y);
  // x lines (one per y, z), then y lines (per x, z), then z lines (per x, y); lines of one pass are
  // independent, so they are split among threads by their outer index.
  forEachBlockInParallel(d.z, [&](int z0, int z1) {
    std::vector<double> f, zz;
    std::vector<int> v;
    for (int z = z0; z < z1; ++z)
      for (int y = 0; y < d.y; ++y) transformLine(&sq[nx * y + nxy * z], 1, d.x, g.spacingMm[0], f, v, zz);
    for (int z = z0; z < z1; ++z)
      for (int x = 0; x < d.x; ++x) transformLine(&sq[std::size_t(x) + nxy * z], nx, d.y, g.spacingMm[1], f, v, zz);
  });
  forEachBlockInParallel(d.y, [&](int y0, int y1) {
    std::vector<double> f, zz;
    std::vector<int> v;
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < d.x; ++x) transformLine(&sq[std::size_t(x) + nx * y], nxy, d.z, g.spacingMm[2], f, v, zz);
  });
  FloatVolume out(g);
  for (std::size_t i = 0; i < sq.size(); ++i) out.voxels[i] = float(std::sqrt(sq[i]));
  return out;
}

Mask dilate(const Mask& mask, double radiusMm) {
  const FloatVolume distance = distanceToMask(mask);
  Mask out(mask.geometry, 0);
  for (std::size_t i = 0; i < out.voxels.size(); ++i) out.voxels[i] = distance.voxels[i] <= radiusMm ? 1 : 0;
  return out;
}

Mask erode(const Mask& mask, double radiusMm) {
  Mask outside(mask.geometry, 0);
  for (std::size_t i = 0; i < outside.voxels.size(); ++i) outside.voxels[i] = mask.voxels[i] ? 0 : 1;
  const FloatVolume distance = distanceToMask(outside);
  Mask out(mask.geometry, 0);
  for (std::size_t i = 0; i < out.voxels.size(); ++i) out.voxels[i] = mask.voxels[i] && distance.voxels[i] > radiusMm;
  return out;
}

Mask open(const Mask& mask, double radiusMm) { return dilate(erode(mask, radiusMm), radiusMm); }

Mask close(const Mask& mask, double radiusMm) { return erode(dilate(mask, radiusMm), radiusMm); }

}  // namespace at::segment
