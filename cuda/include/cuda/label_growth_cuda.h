// The CUDA engine of the multi-label growth (wdt/label_growth.h, wdt/growth_engine.h). Nothing here
// exposes CUDA types.
//
// The state — a 64-bit (distance, label) key and a density byte per voxel, 9 bytes a voxel, plus
// two ints per 16³ brick — stays on the device between updates. An update resets the voxels that
// grew from the removed or relabelled seeds (found on the old pairs as the CPU engine finds them,
// wdt/growth_engine.h; the first such edit allocates 4.125 more bytes a voxel for the search) and
// writes the new seeds (small kernels that also queue the bricks they touch), then one
// cooperative kernel runs rounds over the queued bricks, as the WDT's brick
// solver does (cuda/src/brick_solver.h): each active brick is loaded with its halo into shared
// memory by one block, swept once x+ x− y+ y− z+ z− with wdt::relaxLabelledVoxel (the CPU engine's
// stencil), and its decreased voxels stored; neighbours whose halo holds a decreased voxel, and the
// brick itself if anything decreased, are queued for the next round. Keys only decrease and move
// as single 64-bit loads and stores, so halos are read straight from the state (no snapshots);
// the result is the one fixed point, bit for bit the CPU engine's and the exact reference's.
#pragma once

#include <memory>

#include "volume/error.h"
#include "wdt/growth_engine.h"

namespace at::cuda {

// Uploads the problem's density bytes and allocates the state. Errors: no device, a grid of 2^32
// voxels or more, an allocation failure (naming the call and the byte count).
Result<std::unique_ptr<GrowthEngine>> makeCudaGrowthEngine(const GrowthProblem& problem);

}  // namespace at::cuda
