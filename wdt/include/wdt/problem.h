// The backend-facing form of a WDT request: everything a backend needs on the grid it computes
// on (the volume's grid, or the coarser one when downsampling). The front end (computeWdt) builds
// it — windowing HU to density bytes, aggregating blocks when downsampling, marking seeds — and
// hands it to the CPU or CUDA backend. Backends never see HU or the full-resolution volume.
#pragma once

#include <cstdint>
#include <vector>

#include "volume/grid.h"
#include "wdt/wdt.h"

namespace at {

struct WdtProblem {
  Geometry grid;                       // the grid the field is computed on
  std::vector<std::uint8_t> density;   // densityByte() per voxel (stencil.h); size grid.dims.count()
  std::vector<std::uint8_t> seeds;     // 1 = seed voxel (D = 0); size grid.dims.count()
  WdtParams params;                    // rule, weight rule, baseCost, passes/converge/maxPasses
};

// Coarse grid of a downsampling by `factor`: ceil(dims / factor) voxels, spacing × factor, same
// direction, origin at the centre of the first block (fine index (factor − 1)/2 on each axis).
Geometry downsampledGrid(const Geometry& fine, int factor);

// The density byte of every int16 HU value under the params' window: entry h + 32768 is
// wdt::densityByte(h, huMin, huMax). Backends that build problems themselves (on the GPU) use it
// so that their bytes equal prepareWdtProblem's.
std::vector<std::uint8_t> densityTable(const WdtParams& params);

// Builds the problem for `params` (downsampling included). Errors as computeWdt.
Result<WdtProblem> prepareWdtProblem(const Volume& volume, const Mask& seeds, const WdtParams& params);

// The CPU backend: multi-threaded, vectorised multi-axis sweeps.
Result<WdtResult> runCpuBackend(const WdtProblem& problem, const WdtControl& control);

// The exact reference on the problem's own grid (coarse when downsampled): Dijkstra with the
// same step costs, bit for bit, as the sweeps. exactWdt is this on the full-resolution problem.
Result<FloatVolume> exactWdtOnProblem(const WdtProblem& problem);

}  // namespace at
