// The distance fields that answer keys are computed from — one recipe for grading (the learning
// session's key computer), for the locate click in the desktop app (asked of the field service)
// and for the tests: density weights, the paper's entering rule, sweeps until converged, on a grid
// coarser by 2 per axis (as the paper does for interaction: 8x fewer voxels), sampled back
// trilinearly onto the label grid. Keys compare distances between structures millimetres apart,
// and a relation key must win by a margin, so the coarser grid does not change them.
#pragma once

#include <optional>

#include "core/error.h"
#include "volume/grid.h"
#include "wdt/wdt.h"

namespace at::wdt {

// The recipe's parameters (backend auto).
WdtParams answerKeyParams();

// The field from `seeds` on `volume` computed with answerKeyParams(), on the label grid `labelGrid`.
Result<FloatVolume> answerKeyDistances(const Volume& volume, const Geometry& labelGrid, const Mask& seeds);

// The value answerKeyDistances' volume has at the `labelGrid` voxel nearest to `pointMm`, sampled
// from `field` (computed with answerKeyParams(), still on its coarse grid) without upsampling the
// rest; nullopt outside the grid or where the point is unreachable.
std::optional<double> answerKeyDistanceAt(const DistanceField& field, const Geometry& labelGrid, const Vec3& pointMm);

}  // namespace at::wdt
