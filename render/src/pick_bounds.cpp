#include "render/pick_bounds.h"

#include <algorithm>
#include <cmath>

namespace at::render {

namespace {

// Grows `box` (index space: min i j k, max i j k) by the voxels of `grid` where `inside` holds.
template <typename T, typename Inside>
void growBox(const Grid<T>& grid, Inside inside, std::array<double, 6>& box) {
  const Dims& d = grid.geometry.dims;
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i)
        if (inside(grid.voxels[d.index(i, j, k)])) {
          box[0] = std::min(box[0], double(i)), box[1] = std::min(box[1], double(j)), box[2] = std::min(box[2], double(k));
          box[3] = std::max(box[3], double(i)), box[4] = std::max(box[4], double(j)), box[5] = std::max(box[5], double(k));
        }
}

// The pixel box (x0, y0, x1, y1, inclusive, clamped) that the 8 corners of `box` (an index box of
// `g`, grown by one voxel) project into; nullopt when a corner lies behind the eye.
std::optional<std::array<int, 4>> projectedBox(const Geometry& g, const std::array<double, 6>& box,
                                               const RenderSettings& view) {
  double x0 = 1e300, y0 = 1e300, x1 = -1e300, y1 = -1e300;
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 ijk = {corner & 1 ? box[3] + 1 : box[0] - 1, corner & 2 ? box[4] + 1 : box[1] - 1,
                      corner & 4 ? box[5] + 1 : box[2] - 1};
    const auto p = view.camera.project(g.indexToPatient(ijk), view.width, view.height);
    if (!p) return std::nullopt;
    x0 = std::min(x0, (*p)[0]), y0 = std::min(y0, (*p)[1]), x1 = std::max(x1, (*p)[0]), y1 = std::max(y1, (*p)[1]);
  }
  const auto clampTo = [](double v, int n) { return int(std::clamp(v, -1.0, double(n))); };
  return std::array<int, 4>{clampTo(std::floor(x0) - 1, view.width), clampTo(std::floor(y0) - 1, view.height),
                            clampTo(std::ceil(x1) + 1, view.width), clampTo(std::ceil(y1) + 1, view.height)};
}

}  // namespace

std::optional<std::array<int, 4>> pixelsThatCanPick(const LabelMap& labels, std::uint16_t label, const FloatVolume* field,
                                                    double toleranceMm, const RenderSettings& view) {
  // A pick names the target only on its voxels (the label under the hit point).
  std::array<double, 6> labelBox{1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
  growBox(labels, [&](std::uint16_t v) { return v == label; }, labelBox);
  std::optional<std::array<int, 4>> box;
  if (labelBox[0] <= labelBox[3]) {
    box = projectedBox(labels.geometry, labelBox, view);
    if (!box) return std::nullopt;
  }
  if (field && toleranceMm > 0) {  // or within the tolerance: the field's voxels at most that far
    std::array<double, 6> near{1e300, 1e300, 1e300, -1e300, -1e300, -1e300};
    growBox(*field, [&](float d) { return d >= 0 && d <= toleranceMm + 1e-6; }, near);
    if (near[0] <= near[3]) {
      auto more = projectedBox(field->geometry, near, view);
      if (!more) return std::nullopt;
      if (!box) box = more;
      else
        *box = {std::min((*box)[0], (*more)[0]), std::min((*box)[1], (*more)[1]), std::max((*box)[2], (*more)[2]),
                std::max((*box)[3], (*more)[3])};
    }
  }
  if (!box) return std::array<int, 4>{0, 0, -1, -1};  // nothing picks it
  return box;
}

}  // namespace at::render
