#include "slice_views.h"

#include <algorithm>
#include <cmath>

#include "volume/slice_image.h"

namespace at::app {

namespace {

// The picture's (column, row) axes of a slice across `axis` (volume/slice_image.h).
std::array<int, 2> pictureAxes(int axis) { return {axis == 0 ? 1 : 0, axis == 2 ? 1 : 2}; }

}  // namespace

void SliceViews::attach(const Dataset& dataset) {
  dataset_ = &dataset;
  const Dims d = dataset.volume.dims();
  crosshair_ = {d.x / 2, d.y / 2, d.z / 2};
  const IntensityModel& m = dataset.intensity;
  if (m.hounsfield()) {  // the slice command's default: 400 ± 1000 HU, bone and soft tissue
    centre_ = (400 - m.intercept) / m.slope;
    width_ = 2000 / m.slope;
  } else {
    centre_ = 0.5 * (m.window[0] + m.window[1]);
    width_ = std::max(1e-3, double(m.window[1] - m.window[0]));
  }
  ++revision_;
}

Status SliceViews::setCrosshair(const std::array<int, 3>& voxel) {
  if (!dataset_) return fail(ErrorKind::Unavailable, "slices: no dataset is open");
  const Dims d = dataset_->volume.dims();
  if (!d.contains(voxel[0], voxel[1], voxel[2]))
    return fail("slices: voxel (" + std::to_string(voxel[0]) + ", " + std::to_string(voxel[1]) + ", " +
                std::to_string(voxel[2]) + ") is outside the volume (" + d.toString() + ")");
  if (voxel != crosshair_) ++revision_;
  crosshair_ = voxel;
  return {};
}

bool SliceViews::moveToPoint(const Vec3& pointMm) {
  if (!dataset_) return false;
  const Vec3 ijk = dataset_->volume.geometry.patientToIndex(pointMm);
  const std::array<int, 3> voxel{int(std::lround(ijk[0])), int(std::lround(ijk[1])), int(std::lround(ijk[2]))};
  return bool(setCrosshair(voxel));
}

bool SliceViews::clickPane(int axis, int scale, double x, double y) {
  if (!dataset_ || axis < 0 || axis > 2) return false;
  SliceRequest request;
  request.axis = axis;
  request.index = crosshair_[std::size_t(axis)];
  request.scale = scale;
  const auto voxel = sliceVoxelAt(dataset_->volume.dims(), request, x, y);
  return voxel && setCrosshair(*voxel);
}

void SliceViews::dragWindow(double dx, double dy) {
  if (dx == 0 && dy == 0) return;
  width_ = std::clamp(width_ * std::exp(dx / 200.0), 1e-3, 1e7);
  centre_ -= dy * width_ / 256.0;
  ++revision_;
}

std::array<double, 2> SliceViews::pixelMm(int axis) const {
  if (!dataset_ || axis < 0 || axis > 2) return {1, 1};
  const auto& sp = dataset_->volume.geometry.spacingMm;
  const auto uv = pictureAxes(axis);
  return {sp[std::size_t(uv[0])], sp[std::size_t(uv[1])]};
}

Result<RgbImage> SliceViews::pane(int axis, int scale, const LabelMap* labels, const std::vector<Structure>& structures) const {
  if (!dataset_) return fail(ErrorKind::Unavailable, "slices: no dataset is open");
  SliceRequest request;
  request.axis = axis;
  request.index = axis >= 0 && axis <= 2 ? crosshair_[std::size_t(axis)] : 0;
  request.scale = scale;
  request.windowCentreHu = centre_;
  request.windowWidthHu = width_;
  request.labelAlpha = labels && !labels->empty() ? labelAlpha : 0.0;
  auto image = renderSlice(dataset_->volume, labels && !labels->empty() ? labels : nullptr, structures, request);
  if (!image) return image;
  // The crosshair: the column of its u coordinate and the row of its v coordinate, through the
  // middle of their voxels (rows run down from the highest k on x and y slices).
  const Dims d = dataset_->volume.dims();
  const auto uv = pictureAxes(axis);
  const int extentV = uv[1] == 1 ? d.y : d.z;
  const int col = crosshair_[std::size_t(uv[0])];
  const int row = uv[1] == 2 ? extentV - 1 - crosshair_[2] : crosshair_[std::size_t(uv[1])];
  const std::uint8_t yellow[3] = {255, 220, 40};
  const int x = col * scale + scale / 2, y = row * scale + scale / 2;
  for (int py = 0; py < image->height; ++py) std::copy(yellow, yellow + 3, image->pixel(x, py));
  for (int px = 0; px < image->width; ++px) std::copy(yellow, yellow + 3, image->pixel(px, y));
  return image;
}

}  // namespace at::app
