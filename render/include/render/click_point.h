// Where a student clicks a structure in a picture: the middle of where it lies there — the pixel of
// its projection farthest from the projection's edge.
//
// Why not the structure's anchor (StructureFrame::anchorMm, the voxel nearest its centroid): for a
// structure in two parts (the ethmoid's two labyrinths, the mandible's two rami) the centroid lies
// between them and the anchor at the inner edge of one part, where a click meets the part's
// neighbour first though the parts may be in plain sight; a student clicks the middle of a part.
// The middle of the projection is that, for one part or several (it lies in the widest), and it
// is the same whatever lies in front: whether a click there picks the structure (not what hides
// it) is the caller's question.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "render/camera.h"
#include "volume/grid.h"

namespace at::render {

// Marked pixels of a picture on a grid: every `step`-th pixel of each axis from (x0, y0), `cols` ×
// `rows` of them, row by row. Outside the grid nothing is marked.
struct PixelGrid {
  int x0 = 0, y0 = 0, step = 1, cols = 0, rows = 0;
  std::vector<char> on;  // cols × rows, row-major; non-zero: marked
};

struct DeepestPixel {
  double x = 0, y = 0;  // the pixel (in the picture's pixels)
  // How far it lies from the nearest unmarked grid pixel (or the grid's edge), in pixels (chamfer
  // distance, 1 and √2 per cell, times step).
  double depthPx = 0;
  int markedPixels = 0;  // marked grid pixels, times step²
};

// The marked pixel deepest inside the marked area (ties: the first in row order); nullopt when none
// is marked or the grid does not match its size.
std::optional<DeepestPixel> deepestPixel(const PixelGrid& grid);

// Where voxels labelled `label` lie in a width × height picture from `camera`, on every `step`-th
// pixel: each voxel the clip plane keeps marks the grid pixels within half its projected size
// (at least one) of its centre's projection. The grid covers the whole picture.
PixelGrid footprintOf(const LabelMap& labels, std::uint16_t label, const Camera& camera, int width, int height,
                      const std::optional<ClipPlane>& clip, int step);

// The middle of where the structure lies in the picture: deepestPixel(footprintOf(...)); nullopt
// when none of it lies in the picture.
std::optional<DeepestPixel> middleOfStructure(const LabelMap& labels, std::uint16_t label, const Camera& camera, int width,
                                              int height, const std::optional<ClipPlane>& clip, int step = 2);

}  // namespace at::render
