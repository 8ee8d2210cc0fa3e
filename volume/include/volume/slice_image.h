// One slice of a volume as an RGB image (the `slice` command, exam locate items on slices): grey
// from a HU window, each labelled structure optionally overlaid in its colour.
//
// Image axes: columns along u, rows along v, where (u, v) = (j, k) for an x slice, (i, k) for y and
// (i, j) for z; v runs downwards from the highest k for x and y slices (superior at the top in LPS
// data). Each voxel is `scale` × `scale` pixels. With a `layout` (volume/slice_orientation.h,
// e.g. patientSliceLayout) the picture follows it instead and `axis` is ignored.
#pragma once

#include <array>
#include <optional>
#include <vector>

#include "volume/grid.h"
#include "volume/png_image.h"
#include "volume/slice_orientation.h"
#include "volume/structure.h"

namespace at {

struct SliceRequest {
  int axis = 2;                  // 0, 1, 2: the voxel axis the slice is perpendicular to
  int index = 0;                 // the slice along that axis (0-based)
  double windowCentreHu = 400;
  double windowWidthHu = 2000;   // > 0
  double labelAlpha = 0;         // 0 = no label overlay … 1 = labels opaque
  int scale = 1;                 // pixels per voxel side, >= 1
  std::optional<SliceLayout> layout;  // null: voxel order across `axis` (voxelSliceLayout)
};

// Errors: an axis other than 0..2, an index outside the volume, a window width <= 0, scale < 1.
Result<RgbImage> renderSlice(const Volume& volume, const LabelMap* labels, const std::vector<Structure>& structures,
                             const SliceRequest& request);

// `image` (renderSlice's, one pixel per voxel) with square pixels in millimetres: where a voxel is
// longer along the columns or the rows (`pixelMm`: mm of one pixel along each), that direction is
// stretched by nearest neighbour so a pixel spans the shorter side both ways, and the picture has
// the anatomy's proportions (a 3.2 × 3.2 × 1.5 mm head CT's sagittal slice is 2.1 × as wide as its
// voxel count). Returns the side of a pixel in mm through `squareMm`.
RgbImage withSquarePixels(const RgbImage& image, std::array<double, 2> pixelMm, double* squareMm = nullptr);

// The voxel shown at pixel (x, y) of renderSlice's image; nullopt outside it.
std::optional<std::array<int, 3>> sliceVoxelAt(const Dims& dims, const SliceRequest& request, double x, double y);

}  // namespace at
