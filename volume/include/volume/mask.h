// Structure masks and simple measurements on label maps.
#pragma once

#include <cstddef>
#include <cstdint>

#include "volume/grid.h"

namespace at {

// Voxels whose label equals `label` (1) or not (0), on the label map's grid.
Mask structureMask(const LabelMap& labels, std::uint16_t label);

struct VoxelBox {
  int min[3] = {0, 0, 0};
  int max[3] = {-1, -1, -1};  // inclusive; max < min means empty
  bool empty() const { return max[0] < min[0]; }
};

struct MaskStats {
  std::size_t voxelCount = 0;
  VoxelBox box;                 // bounding box in voxel indices
  Vec3 centroidMm{0, 0, 0};     // mean voxel centre in LPS millimetres
  Vec3 boxMinMm{0, 0, 0};       // bounding box corners (voxel centres) in LPS millimetres
  Vec3 boxMaxMm{0, 0, 0};
};

MaskStats measureMask(const Mask& mask);
MaskStats measureLabel(const LabelMap& labels, std::uint16_t label);

// Number of 26-connected components of the non-zero voxels.
int countComponents(const Mask& mask);

}  // namespace at
