// "Show me on a slice": a frame round a structure on a slice picture (the desktop's answer slice,
// the terminal's), so that a small structure's few coloured pixels are found at a glance.
#pragma once

#include <cstdint>

#include "volume/grid.h"
#include "volume/png_image.h"
#include "volume/slice_image.h"

namespace at::app {

// Draws a frame `thickness` pixels wide, `margin` pixels outside the box of the pixels of `image`
// (made by renderSlice with `request`) whose voxel carries `label`, in yellow, clipped to the
// picture. False (nothing drawn) when no pixel shows the structure.
bool frameStructureOnSlice(RgbImage& image, const LabelMap& labels, const SliceRequest& request, std::uint16_t label,
                           int margin = 6, int thickness = 2);

}  // namespace at::app
