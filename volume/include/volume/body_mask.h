// The body in a scan: what is anatomy, as opposed to the CT table, a headrest, a cushion or
// positioning aids, which render as context if nothing leaves them out.
//
// bodyMask: voxels at or above `tissueLevel` (soft tissue: −300 HU for CT), eroded by a cube of
// `neckMm` half-width, so a thin contact between the body and a headrest or table does not join
// them. The largest 6-connected piece left is the body's core; pieces of 1 cm³ or more apart from
// it are other objects' cores. The thresholded voxels are then shared between the cores by a
// growth inside them (6-connected, each voxel to the core it is fewest steps from): thin parts of
// the body reached only from its core (the nose with the nasal bones, the ears) are body whatever
// their length, a thin contact is split where the growths meet, and thresholded voxels no core
// reaches are not body. Last, holes are filled slice by slice along each axis (air in the sinuses,
// airway and bowel is inside the body). Computed once per dataset: a few passes over the volume.
#pragma once

#include <cstdint>

#include "volume/grid.h"

namespace at {

Mask bodyMask(const Volume& volume, double tissueLevel, double neckMm = 3.0);

// `volume` with every voxel outside `body` (same grid) set to `background`; the number changed.
std::size_t clearOutsideBody(Volume& volume, const Mask& body, std::int16_t background);

}  // namespace at
