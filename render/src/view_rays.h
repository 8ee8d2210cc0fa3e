// Internal to render/: marching a view's rays through a volume's and a field's grids, shared by the
// distance unit's measures (field_scale.cpp, neighbour_scale.cpp).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/parallel_rows.h"
#include "render/camera.h"
#include "volume/grid.h"

namespace at::render::detail {

// Index-space position along a ray: origin + t · perMm.
struct IndexRay {
  Vec3 origin, perMm;
};
inline IndexRay indexRay(const Geometry& g, const Ray& r) {
  const Vec3 o = g.patientToIndex(r.origin);
  return {o, g.patientToIndex(r.origin + r.direction) - o};
}
// The voxel nearest the ray's point at t; false outside the grid.
inline bool voxelOn(const IndexRay& r, double t, const Dims& dims, int ijk[3]) {
  const int n[3] = {dims.x, dims.y, dims.z};
  for (int a = 0; a < 3; ++a) {
    ijk[a] = int(std::lround(r.origin[a] + t * r.perMm[a]));
    if (ijk[a] < 0 || ijk[a] >= n[a]) return false;
  }
  return true;
}
// The ray's segment [t0, t1) inside the grid's box (voxel centres −0.5 … n − 0.5); t0 ≥ 0, and
// t0 ≥ t1 where it misses the box.
inline void boxSegment(const IndexRay& r, const Dims& dims, double& t0, double& t1) {
  const double n[3] = {double(dims.x), double(dims.y), double(dims.z)};
  t0 = 0;
  t1 = 1e300;
  for (int a = 0; a < 3; ++a) {
    if (std::fabs(r.perMm[a]) < 1e-12) {
      if (r.origin[a] < -0.5 || r.origin[a] > n[a] - 0.5) t1 = -1;
      continue;
    }
    double ta = (-0.5 - r.origin[a]) / r.perMm[a], tb = (n[a] - 0.5 - r.origin[a]) / r.perMm[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
}
// The measuring rays' image: at most `raysPerSide` rays along the view's longer side, at pixel
// centres of an image of the same aspect (the same frustum).
struct RayGrid {
  int width = 0, height = 0;
};
inline RayGrid rayGridOf(int viewWidth, int viewHeight, int raysPerSide) {
  if (viewWidth < 1 || viewHeight < 1) return {};
  const double shrink = std::min(1.0, double(raysPerSide) / double(std::max(viewWidth, viewHeight)));
  return {std::max(1, int(std::lround(viewWidth * shrink))), std::max(1, int(std::lround(viewHeight * shrink)))};
}

// City-block distance in rays from the rays that meet the structure (`structure` non-zero; a large
// value everywhere without any), on a w × h ray grid.
inline std::vector<int> raysFromStructure(const std::vector<char>& structure, int w, int h) {
  std::vector<int> d(structure.size(), 1 << 20);
  for (std::size_t i = 0; i < structure.size(); ++i)
    if (structure[i]) d[i] = 0;
  const auto at = [&](int x, int y) -> int& { return d[std::size_t(y) * std::size_t(w) + std::size_t(x)]; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (x > 0) at(x, y) = std::min(at(x, y), at(x - 1, y) + 1);
      if (y > 0) at(x, y) = std::min(at(x, y), at(x, y - 1) + 1);
    }
  for (int y = h - 1; y >= 0; --y)
    for (int x = w - 1; x >= 0; --x) {
      if (x + 1 < w) at(x, y) = std::min(at(x, y), at(x + 1, y) + 1);
      if (y + 1 < h) at(x, y) = std::min(at(x, y), at(x, y + 1) + 1);
    }
  return d;
}

}  // namespace at::render::detail
