#include "render/click_point.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace at::render {

std::optional<DeepestPixel> deepestPixel(const PixelGrid& grid) {
  const int w = grid.cols, h = grid.rows;
  if (w <= 0 || h <= 0 || grid.on.size() != std::size_t(w) * std::size_t(h)) return std::nullopt;
  // Chamfer distance (1, √2) in cells from each marked cell to the nearest unmarked one, the cells
  // beyond the grid counting as unmarked (a marked cell on the edge is 1 away).
  constexpr double kDiagonal = 1.4142135623730951;
  std::vector<double> d(grid.on.size());
  const auto at = [&](int x, int y) -> double {
    if (x < 0 || y < 0 || x >= w || y >= h) return 0.0;
    return d[std::size_t(y) * std::size_t(w) + std::size_t(x)];
  };
  for (std::size_t i = 0; i < d.size(); ++i) d[i] = grid.on[i] ? std::numeric_limits<double>::infinity() : 0.0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double& v = d[std::size_t(y) * std::size_t(w) + std::size_t(x)];
      if (v == 0) continue;
      v = std::min({v, at(x - 1, y) + 1, at(x, y - 1) + 1, at(x - 1, y - 1) + kDiagonal, at(x + 1, y - 1) + kDiagonal});
    }
  for (int y = h - 1; y >= 0; --y)
    for (int x = w - 1; x >= 0; --x) {
      double& v = d[std::size_t(y) * std::size_t(w) + std::size_t(x)];
      if (v == 0) continue;
      v = std::min({v, at(x + 1, y) + 1, at(x, y + 1) + 1, at(x + 1, y + 1) + kDiagonal, at(x - 1, y + 1) + kDiagonal});
    }
  std::optional<DeepestPixel> best;
  int marked = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double v = d[std::size_t(y) * std::size_t(w) + std::size_t(x)];
      if (v == 0) continue;
      ++marked;
      if (!best || v * grid.step > best->depthPx)
        best = DeepestPixel{double(grid.x0 + x * grid.step), double(grid.y0 + y * grid.step), v * grid.step, 0};
    }
  if (best) best->markedPixels = marked * grid.step * grid.step;
  return best;
}

PixelGrid footprintOf(const LabelMap& labels, std::uint16_t label, const Camera& camera, int width, int height,
                      const std::optional<ClipPlane>& clip, int step) {
  PixelGrid g;
  g.step = std::max(1, step);
  g.cols = width > 0 ? (width - 1) / g.step + 1 : 0;
  g.rows = height > 0 ? (height - 1) / g.step + 1 : 0;
  g.on.assign(std::size_t(g.cols) * std::size_t(g.rows), 0);
  if (g.on.empty()) return g;
  const Geometry& geo = labels.geometry;
  const Dims& d = geo.dims;
  const double voxelMm = std::max({geo.spacingMm[0], geo.spacingMm[1], geo.spacingMm[2]});
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        if (labels.voxels[d.index(i, j, k)] != label) continue;
        const Vec3 p = geo.indexToPatient({double(i), double(j), double(k)});
        if (clip && !clip->keeps(p)) continue;
        const auto c = camera.project(p, width, height);
        if (!c) continue;
        // Half the voxel's projected size: the projection of a point half a voxel off along the
        // screen's up axis.
        double r = 0.5;
        if (const auto e = camera.project(p + (0.5 * voxelMm) * camera.up(), width, height))
          r = std::max(0.5, std::hypot((*e)[0] - (*c)[0], (*e)[1] - (*c)[1]));
        const int gx0 = int(std::ceil(((*c)[0] - r) / g.step)), gx1 = int(std::floor(((*c)[0] + r) / g.step));
        const int gy0 = int(std::ceil(((*c)[1] - r) / g.step)), gy1 = int(std::floor(((*c)[1] + r) / g.step));
        const int nearestX = int(std::lround((*c)[0] / g.step)), nearestY = int(std::lround((*c)[1] / g.step));
        bool any = false;
        for (int gy = std::max(0, gy0); gy <= std::min(g.rows - 1, gy1); ++gy)
          for (int gx = std::max(0, gx0); gx <= std::min(g.cols - 1, gx1); ++gx) {
            g.on[std::size_t(gy) * std::size_t(g.cols) + std::size_t(gx)] = 1;
            any = true;
          }
        if (!any && nearestX >= 0 && nearestX < g.cols && nearestY >= 0 && nearestY < g.rows)
          g.on[std::size_t(nearestY) * std::size_t(g.cols) + std::size_t(nearestX)] = 1;
      }
  return g;
}

std::optional<DeepestPixel> middleOfStructure(const LabelMap& labels, std::uint16_t label, const Camera& camera, int width,
                                              int height, const std::optional<ClipPlane>& clip, int step) {
  return deepestPixel(footprintOf(labels, label, camera, width, height, clip, step));
}

}  // namespace at::render
