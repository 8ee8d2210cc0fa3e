// Bricks: cubes of `edge` voxels tiling a grid, the unit of work of the brick rounds (the WDT's
// CUDA converge mode) and of both multi-label growth engines. A voxel on a brick's face lies in
// the one-voxel halo of the neighbour bricks across that face, edge or corner; a change of it must
// queue those bricks. Usable from C++ and CUDA.
#pragma once

#include "wdt/step_cost.h"

namespace at::wdt {

// Bits (dx + 1) + 3·(dy + 1) + 9·(dz + 1) of the neighbour bricks whose halo holds the brick's
// voxel (x, y, z) (0 … edge − 1 on each axis): one per face, edge and corner the voxel lies on.
AT_FORCE_INLINE unsigned brickNeighbourMask(int x, int y, int z, int edge) {
  const int e[3] = {x == 0 ? -1 : (x == edge - 1 ? 1 : 0), y == 0 ? -1 : (y == edge - 1 ? 1 : 0),
                    z == 0 ? -1 : (z == edge - 1 ? 1 : 0)};
  unsigned mask = 0;
  AT_UNROLL for (int s = 1; s < 8; ++s) {  // non-empty subsets of the axes
    const int dx = (s & 1) ? e[0] : 0, dy = (s & 2) ? e[1] : 0, dz = (s & 4) ? e[2] : 0;
    if (((s & 1) && !e[0]) || ((s & 2) && !e[1]) || ((s & 4) && !e[2])) continue;
    mask |= 1u << ((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1));
  }
  return mask;
}

}  // namespace at::wdt
