// The values a growth's step costs are computed from (label_growth.h, GrowthParams): the stored
// values as they are, blurred by a Gaussian, or smoothed so that edges stay (bilateral). Private to
// wdt/src.
#pragma once

#include <vector>

#include "volume/grid.h"

namespace at::wdt {

// The values blurred by a Gaussian of `sigmaVoxels` voxels along each axis (separable, taps out to
// 2.5 sigma, the border value repeated).
std::vector<float> gaussianSmoothed(const Volume& volume, float sigmaVoxels);

// Edge-preserving (bilateral) smoothing: each voxel becomes the mean of its neighbours within
// ⌈2·sigmaVoxels⌉ voxels (at most 3) weighted by exp(−r²/2σ²) in space and exp(−Δ²/2·edgeSigma²)
// in value (Δ the difference of stored values). Differences of a few edgeSigma keep almost no
// weight, so an edge much stronger than edgeSigma stays sharp while noise of about edgeSigma
// averages out (a thin bone of high contrast keeps its voxels, an organ's interior gets smooth).
std::vector<float> edgePreservingSmoothed(const Volume& volume, float sigmaVoxels, float edgeSigma);

}  // namespace at::wdt
