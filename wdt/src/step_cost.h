// Internal to wdt/: the step cost of every (rule, weight) combination as one small set of inline
// functions, shared by the CPU sweeps and the exact reference so that both add the same float to
// D(a). Built on the stencil.h primitives the CUDA backend uses.
#pragma once

#include <cstdint>

#include "wdt/stencil.h"
#include "wdt/wdt.h"

namespace at::wdt {

// The cost kernels. Uniform weights (w = 1) make both rules the same cost, len, bit for bit
// (½(1 + 1)·len = len), so both map to EnterUniform. Gradient and ascent weights belong to the
// step a → b, not to a voxel; both rules then charge w(a→b)·|step|.
enum class CostKernel { EnterDensity, EnterUniform, TrapezoidDensity, EdgeGradient, EdgeAscent };

inline CostKernel costKernel(const WdtParams& p) {
  switch (p.weight) {
    case WeightRule::Uniform: return CostKernel::EnterUniform;
    case WeightRule::Gradient: return CostKernel::EdgeGradient;
    case WeightRule::Ascent: return CostKernel::EdgeAscent;
    case WeightRule::Density: break;
  }
  return p.rule == StepRule::Trapezoid ? CostKernel::TrapezoidDensity : CostKernel::EnterDensity;
}

// Cost of the step a → b (density bytes qa, qb) of length `len`.
template <CostKernel K>
inline __attribute__((always_inline)) float stepCost(std::uint8_t qa, std::uint8_t qb, float len, float base) {
  if constexpr (K == CostKernel::EnterDensity) {
    return enteringStepCost(densityWeight(qb, base), len);
  } else if constexpr (K == CostKernel::EnterUniform) {
    return enteringStepCost(1.0f, len);
  } else if constexpr (K == CostKernel::TrapezoidDensity) {
    return trapezoidStepCost(densityWeight(qa, base), densityWeight(qb, base), len);
  } else if constexpr (K == CostKernel::EdgeGradient) {
    const float diff = densityFromByte(qb) - densityFromByte(qa);
    return enteringStepCost(base + __builtin_fabsf(diff), len);
  } else {
    const float rise = densityFromByte(qb) - densityFromByte(qa);
    return enteringStepCost(base + (rise > 0.0f ? rise : 0.0f), len);
  }
}

// Update of one voxel (current value cur, density byte qb) from its 9 neighbours nb[dc][db] in the
// previous plane (db along the row, dc across rows; densities qn, read only by kernels that need
// them): the CPU sweeps' per-voxel arithmetic.
template <CostKernel K>
inline __attribute__((always_inline)) float relaxVoxel(float cur, const float nb[3][3], const std::uint8_t qn[3][3],
                                                       std::uint8_t qb, SweepLengths l, float base) {
  if constexpr (K == CostKernel::EnterDensity) {
    return enteringUpdate(cur, nb, densityWeight(qb, base), l);
  } else if constexpr (K == CostKernel::EnterUniform) {
    return enteringUpdate(cur, nb, 1.0f, l);
  } else {
    const float lens[3][3] = {{l.diagonal, l.alongC, l.diagonal},
                              {l.alongB, l.straight, l.alongB},
                              {l.diagonal, l.alongC, l.diagonal}};
    float best = cur;
    for (int dc = 0; dc < 3; ++dc)
      for (int db = 0; db < 3; ++db) best = minf(best, nb[dc][db] + stepCost<K>(qn[dc][db], qb, lens[dc][db], base));
    return best;
  }
}

// Smallest and largest weight (cost per mm) a kernel can produce; the exact reference sizes its
// buckets from them.
inline void weightRange(CostKernel k, float base, float& lo, float& hi) {
  if (k == CostKernel::EnterUniform) {
    lo = hi = 1.0f;
  } else {
    lo = base;
    hi = base + 1.0f;
  }
}

}  // namespace at::wdt
