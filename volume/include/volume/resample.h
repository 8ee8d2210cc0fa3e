// Resampling label maps between grids through both patient frames (nearest neighbour).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/error.h"
#include "volume/grid.h"

namespace at {

// Each target voxel takes the label of the source voxel nearest to its centre in LPS; target
// voxels outside the source grid get 0. Errors if the two grids do not overlap at all.
Result<LabelMap> resampleLabelsNearest(const LabelMap& source, const Geometry& target);

// A label of a source map that no voxel of its resampled map carries: smaller than the target's
// voxels (no target centre falls on it) or outside the target grid.
struct LostLabel {
  std::uint16_t label = 0;
  std::size_t sourceVoxels = 0;  // its voxels in the source map
};

// The non-zero labels of `source` absent from `resampled`, in increasing label order.
std::vector<LostLabel> labelsLostInResampling(const LabelMap& source, const LabelMap& resampled);

}  // namespace at
