// Resampling label maps between grids through both patient frames (nearest neighbour).
#pragma once

#include "core/error.h"
#include "volume/grid.h"

namespace at {

// Each target voxel takes the label of the source voxel nearest to its centre in LPS; target
// voxels outside the source grid get 0. Errors if the two grids do not overlap at all.
Result<LabelMap> resampleLabelsNearest(const LabelMap& source, const Geometry& target);

}  // namespace at
