// Which structure lies under the cursor: the one the pixel shows. Many structures a student points
// at are hollow (air or fluid spaces: canals, the cochlea, the tympanic cavity) and so transparent:
// the first opaque sample (pick(), render_settings.h) is the wall behind them, outside their label.
// This pick walks the ray through the label map from the eye up to a little beyond that first
// opaque sample and takes the first labelled structure it meets on the kept side of the clipping
// plane — unless the view does not draw that structure (the ray shows nothing before leaving it)
// and what the ray then shows is another labelled structure: a muscle the preset leaves out in
// front of a vertebra, an organ in front of the highlighted kidney. Then the one shown is named.
// An unlabelled wall behind an undrawn structure is that structure's own (a canal's bone).
#pragma once

#include "render/render_settings.h"

namespace at::render {

// Context bone is drawn as medium-opacity surfaces that the user sees through, so "the first opaque
// sample" is where the accumulated opacity reaches kSeenThroughOpacity, not one half: a structure
// seen through one or two bone surfaces is still under the cursor.
constexpr double kSeenThroughOpacity = 0.85;
// A structure is drawn along a ray when the accumulated opacity reaches this before the ray leaves it.
constexpr double kVisibleOpacity = 0.1;

// `beyondMm`: how far past the first opaque sample a label still counts (the wall's thickness the
// user perceives as the structure's boundary). With no opaque sample the whole ray is walked.
PickResult pickStructure(const SceneVolumes& scene, const RenderSettings& settings, const TransferFunction2D& table,
                         double x, double y, double beyondMm = 1.0);

}  // namespace at::render
