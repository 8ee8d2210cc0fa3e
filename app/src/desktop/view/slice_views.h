// The desktop's three slice panes — sagittal, coronal and axial in patient orientation
// (radiological convention, volume/slice_orientation.h: patient's left on the screen's right) —
// through one crosshair voxel, without drawing (the Slices window draws them): each pane's picture shown at its
// voxels' aspect (pixelMm), grey in a window the user drags, labels overlaid at an opacity, the
// crosshair's two lines. A click in a pane moves the crosshair there, so the other two panes show
// the slices through the clicked voxel; a pick in the 3-D view moves it to the picked point.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/error.h"
#include "view/grey_window.h"
#include "volume/png_image.h"
#include "volume/slice_orientation.h"
#include "volume/structure.h"

namespace at::app {

class SliceViews {
 public:
  // A dataset is on screen (kept alive by the caller until the next attach): crosshair at its
  // centre, the grey window its intensity model's default (CT: 400 ± 1000 HU).
  void attach(const Dataset& dataset);
  bool attached() const { return dataset_ != nullptr; }
  bool windowOpen = false;
  double labelAlpha = 0.4;  // 0: no overlay … 1: labels opaque

  const std::array<int, 3>& crosshair() const { return crosshair_; }
  // Errors: a voxel outside the grid (named with the grid's size).
  Status setCrosshair(const std::array<int, 3>& voxel);
  // The voxel nearest a point in LPS mm (a 3-D pick); false (nothing moves) outside the grid.
  bool moveToPoint(const Vec3& pointMm);
  // Pane `plane` (PatientPlane: 0 sagittal, 1 coronal, 2 axial) laid out over the dataset's voxel
  // axes by patientSliceLayout, with its edge letters (L R A P S I).
  SliceLayout layout(int plane) const;
  // A click at pixel (x, y) of pane `axis` (a plane as above) drawn at `scale` pixels per voxel: the crosshair moves
  // to that voxel of the pane's slice. False outside the picture.
  bool clickPane(int axis, int scale, double x, double y);
  // A drag of (dx, dy) pixels: right/left widens/narrows the window, down/up lowers/raises its
  // centre (GreyWindow::drag).
  void dragWindow(double dx, double dy);
  std::array<double, 2> window() const { return grey_.centreWidth(); }  // stored values

  // Pane `axis` (a plane as above) through the crosshair, `scale` pixels per voxel, with `labels`
  // (null: none) in their structures' colours and the crosshair's lines. Its pixel → voxel map is
  // sliceVoxelAt (volume/slice_image.h) with layout(axis), the crosshair's index and scale.
  Result<RgbImage> pane(int axis, int scale, const LabelMap* labels, const std::vector<Structure>& structures) const;
  // mm of one picture pixel along its columns and rows (the pane is shown at this aspect).
  std::array<double, 2> pixelMm(int axis) const;
  // Changes whenever a pane's picture would (crosshair, window, opacity are compared by the caller).
  std::uint64_t revision() const { return revision_; }

 private:
  const Dataset* dataset_ = nullptr;
  std::array<int, 3> crosshair_{0, 0, 0};
  GreyWindow grey_;
  std::uint64_t revision_ = 0;
};

}  // namespace at::app
