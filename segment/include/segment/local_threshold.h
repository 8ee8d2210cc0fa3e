// A local threshold: the voxels near a click whose values lie in a range and connect to the click
// through such voxels. The segment editor seeds them (any label, the background included), so one
// large dab in the air beside a thin bone seeds the air and not the bone.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "core/error.h"
#include "volume/grid.h"
#include "volume/intensity.h"

namespace at::segment {

// The voxels within radiusMm of the voxel `centre` (a ball in mm on the grid's spacing) whose
// values (the dataset's: HU or plain intensities, IntensityModel::valueOf) lie in low … high and
// connect to `centre` through such voxels inside the ball (6-connected), in index order. It reads
// only the values, never labels. Errors (one line naming the field): centre outside the grid, a
// negative radius, low > high, the value under the centre outside the range (naming the value).
Result<std::vector<std::size_t>> localThresholdRegion(const Volume& volume, const IntensityModel& intensity,
                                                      const std::array<int, 3>& centre, double radiusMm, double low,
                                                      double high);

}  // namespace at::segment
