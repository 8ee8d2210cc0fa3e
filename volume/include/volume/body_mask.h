// The body in a scan: what is anatomy, as opposed to the CT table, a headrest, a cushion or
// positioning aids, which render as context if nothing leaves them out.
//
// bodyMask: voxels at or above `tissueLevel` (soft tissue: −300 HU for CT), opened by a cube of
// `neckMm` half-width (so a thin contact between the body and a headrest or table does not join
// them), the largest 6-connected component of that kept, grown back within the thresholded voxels
// by the same amount, and its holes filled slice by slice along each axis (air in the sinuses,
// airway and bowel is inside the body). Computed once per dataset: a few passes over the volume.
#pragma once

#include <cstdint>

#include "volume/grid.h"

namespace at {

Mask bodyMask(const Volume& volume, double tissueLevel, double neckMm = 3.0);

// `volume` with every voxel outside `body` (same grid) set to `background`; the number changed.
std::size_t clearOutsideBody(Volume& volume, const Mask& body, std::int16_t background);

}  // namespace at
