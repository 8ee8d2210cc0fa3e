// Device helpers of the sweep kernels, shared by the whole-volume sweeps (exact_sweep.cu), the
// brick rounds (brick_solver.cu) and the multi-label growth (label_growth.cu). The step costs and
// the per-voxel update are wdt/step_cost.h's, the CPU backend's very functions. Private to
// cuda/src.
#pragma once

#include <cstdint>

#include "volume/error.h"
#include "wdt/step_cost.h"

namespace at::cuda {
namespace {

using wdt::CostKernel;

constexpr float kInf = __builtin_huge_valf();

// The 9 previous-plane neighbours of the voxel whose previous-plane cell is `prev[at]`: distances
// n[dc+1][db+1] = prev[at + dc·strideC + db·strideB], and their densities qn from `qPrev` when the
// rule needs them (kNeighbourDensity; otherwise 0 and qPrev is not read).
template <bool kNeighbourDensity>
__device__ __forceinline__ void gatherNeighbours(const float* prev, const std::uint8_t* qPrev, int at, int strideB,
                                                 int strideC, float n[3][3], std::uint8_t qn[3][3]) {
#pragma unroll
  for (int dc = 0; dc < 3; ++dc) {
#pragma unroll
    for (int db = 0; db < 3; ++db) {
      const int i = at + (dc - 1) * strideC + (db - 1) * strideB;
      n[dc][db] = prev[i];
      qn[dc][db] = kNeighbourDensity ? qPrev[i] : 0;
    }
  }
}

// Calls launch.template operator()<K>() with the cost kernel of (rule, weight) (wdt/step_cost.h).
template <class Launch>
Status launchForRule(StepRule rule, WeightRule weight, Launch&& launch) {
  return wdt::withCostKernel(wdt::costKernel(rule, weight),
                             [&]<CostKernel K>() -> Status { return launch.template operator()<K>(); });
}

}  // namespace
}  // namespace at::cuda
