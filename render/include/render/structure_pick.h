// Which structure lies under the cursor. Many structures a student points at are hollow (air or
// fluid spaces: canals, the cochlea, the tympanic cavity) and so transparent: the first opaque
// sample (pick(), render_settings.h) is the wall behind them, outside their label. This pick walks
// the ray through the label map from the eye up to a little beyond that first opaque sample and
// returns the first labelled voxel it meets on the kept side of the clipping plane.
#pragma once

#include "render/render_settings.h"

namespace at::render {

// Context bone is drawn as medium-opacity surfaces that the user sees through, so "the first opaque
// sample" is where the accumulated opacity reaches kSeenThroughOpacity, not one half: a structure
// seen through one or two bone surfaces is still under the cursor.
constexpr double kSeenThroughOpacity = 0.85;

// `beyondMm`: how far past the first opaque sample a label still counts (the wall's thickness the
// user perceives as the structure's boundary). With no opaque sample the whole ray is walked.
PickResult pickStructure(const SceneVolumes& scene, const RenderSettings& settings, const TransferFunction2D& table,
                         double x, double y, double beyondMm = 1.0);

}  // namespace at::render
