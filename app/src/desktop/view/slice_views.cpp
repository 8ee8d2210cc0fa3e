#include "view/slice_views.h"

#include <algorithm>
#include <cmath>

#include "volume/slice_image.h"

namespace at::app {

SliceLayout SliceViews::layout(int plane) const {
  const Mat3 direction = dataset_ ? dataset_->volume.geometry.direction : Mat3::identity();
  return patientSliceLayout(direction, PatientPlane(std::clamp(plane, 0, 2)));
}

void SliceViews::attach(const Dataset& dataset) {
  dataset_ = &dataset;
  const Dims d = dataset.volume.dims();
  crosshair_ = {d.x / 2, d.y / 2, d.z / 2};
  grey_.reset(dataset.intensity);
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
  request.layout = layout(axis);
  request.index = crosshair_[std::size_t(request.layout->sliceAxis)];
  request.scale = scale;
  const auto voxel = sliceVoxelAt(dataset_->volume.dims(), request, x, y);
  return voxel && setCrosshair(*voxel);
}

void SliceViews::dragWindow(double dx, double dy) {
  if (grey_.drag(dx, dy)) ++revision_;
}

std::array<double, 2> SliceViews::pixelMm(int axis) const {
  if (!dataset_ || axis < 0 || axis > 2) return {1, 1};
  const auto& sp = dataset_->volume.geometry.spacingMm;
  const SliceLayout l = layout(axis);
  return {sp[std::size_t(l.columnAxis)], sp[std::size_t(l.rowAxis)]};
}

Result<RgbImage> SliceViews::pane(int axis, int scale, const LabelMap* labels, const std::vector<Structure>& structures) const {
  if (!dataset_) return fail(ErrorKind::Unavailable, "slices: no dataset is open");
  if (axis < 0 || axis > 2) return fail("slices: pane " + std::to_string(axis) + " is not 0, 1 or 2");
  SliceRequest request;
  request.layout = layout(axis);
  request.index = crosshair_[std::size_t(request.layout->sliceAxis)];
  request.scale = scale;
  grey_.applyTo(request);
  request.labelAlpha = labels && !labels->empty() ? labelAlpha : 0.0;
  auto image = renderSlice(dataset_->volume, labels && !labels->empty() ? labels : nullptr, structures, request);
  if (!image) return image;
  // The crosshair: the column and row showing its voxel, through the middle of their blocks.
  const Dims d = dataset_->volume.dims();
  const int extent[3] = {d.x, d.y, d.z};
  const SliceLayout& l = *request.layout;
  const int u = crosshair_[std::size_t(l.columnAxis)], v = crosshair_[std::size_t(l.rowAxis)];
  const int col = l.columnReversed ? extent[l.columnAxis] - 1 - u : u;
  const int row = l.rowReversed ? extent[l.rowAxis] - 1 - v : v;
  const std::uint8_t yellow[3] = {255, 220, 40};
  const int x = col * scale + scale / 2, y = row * scale + scale / 2;
  for (int py = 0; py < image->height; ++py) std::copy(yellow, yellow + 3, image->pixel(x, py));
  for (int px = 0; px < image->width; ++px) std::copy(yellow, yellow + 3, image->pixel(px, y));
  return image;
}

}  // namespace at::app
