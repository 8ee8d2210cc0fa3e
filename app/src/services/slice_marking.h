// "Show me on a slice" and locate-on-slice exam items: the slice through a structure's anchor in
// patient orientation, its edge letters, and a frame round the structure on the picture (the
// desktop's answer slice, the terminal's), so that a small structure's few coloured pixels are
// found at a glance.
#pragma once

#include <cstdint>

#include "volume/grid.h"
#include "volume/png_image.h"
#include "volume/slice_image.h"

namespace at::app {

// The axial slice through the voxel nearest `anchorMm` (clamped into `grid`), laid out in patient
// orientation as the Slices panes lay it out (patientSliceLayout of the grid's direction: seen
// from the feet, anterior up, the patient's left on the right), `scale` pixels per voxel.
SliceRequest anchorSliceRequest(const Geometry& grid, const Vec3& anchorMm, int scale = 1);

// The layout's patient letters (L R A P S I) at the middle of the picture's four edges, inside
// it, in yellow, the 5 × 7 font at `textScale` (render/overlay.h).
void drawSliceEdgeLetters(RgbImage& image, const SliceLayout& layout, int textScale = 2);

// Draws a frame `thickness` pixels wide, `margin` pixels outside the box of the pixels of `image`
// (made by renderSlice with `request`) whose voxel carries `label`, in yellow, clipped to the
// picture. False (nothing drawn) when no pixel shows the structure.
bool frameStructureOnSlice(RgbImage& image, const LabelMap& labels, const SliceRequest& request, std::uint16_t label,
                           int margin = 6, int thickness = 2);

}  // namespace at::app
