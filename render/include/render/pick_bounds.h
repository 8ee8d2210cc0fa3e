// Where on a picture a click can name a structure: the pixels outside which no pick
// (pickStructure, then the label or the field's distance at the hit point) can be the target or
// within a tolerance of it. Lets a locate key try only those pixels instead of every pixel of the
// picture; tests/render/test_pick_bounds.cpp compares the two on random scenes.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "render/render_settings.h"
#include "volume/grid.h"

namespace at::render {

// The pixels (x0, y0, x1, y1 inclusive, clamped to the picture give or take one; x1 < x0 when
// none) of a `view` picture outside which no pick hits a voxel labelled `label` in `labels`, nor —
// when `field` is given and `toleranceMm` > 0 — a point whose nearest `field` voxel holds a distance
// in [0, toleranceMm + 1e-6]: the projection of those voxels, each grown by a voxel. nullopt when
// the grown box reaches behind the eye (any pixel may pick).
std::optional<std::array<int, 4>> pixelsThatCanPick(const LabelMap& labels, std::uint16_t label, const FloatVolume* field,
                                                    double toleranceMm, const RenderSettings& view);

}  // namespace at::render
