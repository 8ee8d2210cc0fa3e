// Per-voxel rules of the sweep kernels, shared by the whole-volume sweeps (exact_sweep.cu) and the
// brick rounds (brick_solver.cu):
// the step costs of every (rule, weight) pair, built on wdt/stencil.h exactly as the CPU backend's
// step_cost.h builds them. Private to cuda/src.
#pragma once

#include <cstdint>

#include "wdt/stencil.h"
#include "wdt/wdt.h"

namespace at::cuda {
namespace {

constexpr float kInf = __builtin_huge_valf();

// Whether the cost of a step depends on the neighbour's (a's) density, not only on b's.
template <StepRule R, WeightRule W>
constexpr bool kNeedsNeighbourDensity = !(R == StepRule::Entering && (W == WeightRule::Density || W == WeightRule::Uniform));

// Cost of one step a → b of length `len`, for rules whose weight involves a (see wdt.h).
template <StepRule R, WeightRule W>
__device__ __forceinline__ float stepCost(std::uint8_t qa, std::uint8_t qb, float len, float base) {
  if constexpr (W == WeightRule::Uniform) {
    return wdt::enteringStepCost(1.0f, len);  // ½(1 + 1)·len = len: both rules, bit for bit
  } else if constexpr (W == WeightRule::Density) {
    const float wb = wdt::densityWeight(qb, base);
    if constexpr (R == StepRule::Entering) return wdt::enteringStepCost(wb, len);
    else return wdt::trapezoidStepCost(wdt::densityWeight(qa, base), wb, len);
  } else {
    const float df = wdt::densityFromByte(qb) - wdt::densityFromByte(qa);
    const float w = base + (W == WeightRule::Gradient ? fabsf(df) : (df > 0.0f ? df : 0.0f));
    return wdt::enteringStepCost(w, len);  // an edge weight: both rules charge w(a→b)·|step|
  }
}

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

// New value of voxel b (current value `cur`, density byte qb) from its previous-plane neighbours
// n[dc+1][db+1] (densities qn, used only when the rule needs them).
template <StepRule R, WeightRule W>
__device__ __forceinline__ float relax(float cur, const float n[3][3], const std::uint8_t qn[3][3], std::uint8_t qb,
                                       const wdt::SweepLengths& l, float base) {
  if constexpr (R == StepRule::Entering && W == WeightRule::Density) {
    return wdt::enteringUpdate(cur, n, wdt::densityWeight(qb, base), l);
  } else if constexpr (R == StepRule::Entering && W == WeightRule::Uniform) {
    return wdt::enteringUpdate(cur, n, 1.0f, l);
  } else {
    float best = cur;
#pragma unroll
    for (int dc = 0; dc < 3; ++dc) {
#pragma unroll
      for (int db = 0; db < 3; ++db) {
        const float len = dc == 1 ? (db == 1 ? l.straight : l.alongB) : (db == 1 ? l.alongC : l.diagonal);
        best = wdt::minf(best, n[dc][db] + stepCost<R, W>(qn[dc][db], qb, len, base));
      }
    }
    return best;
  }
}

// Calls launch.template operator()<R, W>() with the kernel variant of (rule, weight). Only density
// weights tell the two step rules apart: uniform weights cost len under both (½(1 + 1)·len = len
// exactly), gradient and ascent weights belong to the edge a → b and both rules charge w(a→b)·len
// (as the CPU backend's step_cost.h does).
template <class Launch>
Status launchForRule(StepRule rule, WeightRule weight, Launch&& launch) {
  if (rule == StepRule::Trapezoid && weight == WeightRule::Density) {
    return launch.template operator()<StepRule::Trapezoid, WeightRule::Density>();
  }
  switch (weight) {
    case WeightRule::Density: return launch.template operator()<StepRule::Entering, WeightRule::Density>();
    case WeightRule::Uniform: return launch.template operator()<StepRule::Entering, WeightRule::Uniform>();
    case WeightRule::Gradient: return launch.template operator()<StepRule::Entering, WeightRule::Gradient>();
    case WeightRule::Ascent: return launch.template operator()<StepRule::Entering, WeightRule::Ascent>();
  }
  return fail("WDT CUDA backend: unknown weight rule");
}

}  // namespace
}  // namespace at::cuda
