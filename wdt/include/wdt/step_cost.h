// The step cost of every (step rule, weight rule) pair, written once for every backend: the CPU
// sweeps, the exact reference (Dijkstra), the CUDA sweep kernels and brick rounds, and the
// multi-label growth on both (label_growth.h) call these functions, so that one step a → b adds
// the same float to D(a) everywhere and converged fields agree bit for bit.
//
// Usable from C++ and CUDA (AT_HOST_DEVICE, plain values, no std:: calls). Built on the per-voxel
// primitives of stencil.h.
#pragma once

#include <cstdint>

#include "wdt/stencil.h"
#include "wdt/wdt.h"

#if defined(__CUDACC__)
#define AT_FORCE_INLINE __host__ __device__ __forceinline__
#else
#define AT_FORCE_INLINE inline __attribute__((always_inline))
#endif

// Fully unrolled fixed-count loops on the device (the host compilers unroll the 3 × 3 loops anyway).
#if defined(__CUDACC__)
#define AT_UNROLL _Pragma("unroll")
#else
#define AT_UNROLL
#endif

namespace at::wdt {

// The cost kernels. Uniform weights (w = 1) make both rules the same cost, len, bit for bit
// (½(1 + 1)·len = len), so both map to EnterUniform. Gradient and ascent weights belong to the
// step a → b, not to a voxel; both rules then charge w(a→b)·|step|.
enum class CostKernel { EnterDensity, EnterUniform, TrapezoidDensity, EdgeGradient, EdgeAscent };

AT_HOST_DEVICE constexpr CostKernel costKernel(StepRule rule, WeightRule weight) {
  switch (weight) {
    case WeightRule::Uniform: return CostKernel::EnterUniform;
    case WeightRule::Gradient: return CostKernel::EdgeGradient;
    case WeightRule::Ascent: return CostKernel::EdgeAscent;
    case WeightRule::Density: break;
  }
  return rule == StepRule::Trapezoid ? CostKernel::TrapezoidDensity : CostKernel::EnterDensity;
}

inline CostKernel costKernel(const WdtParams& p) { return costKernel(p.rule, p.weight); }

// Whether the cost of a step depends on the neighbour's (a's) density, not only on b's: the
// kernels that must load their neighbours' density bytes.
AT_HOST_DEVICE constexpr bool needsNeighbourDensity(CostKernel k) {
  return k != CostKernel::EnterDensity && k != CostKernel::EnterUniform;
}

AT_FORCE_INLINE float absf_portable(float x) {
#if defined(__CUDA_ARCH__)
  return fabsf(x);
#else
  return __builtin_fabsf(x);
#endif
}

// Cost of the step a → b (density bytes qa, qb) of length `len`.
template <CostKernel K>
AT_FORCE_INLINE float stepCost(std::uint8_t qa, std::uint8_t qb, float len, float base) {
  if constexpr (K == CostKernel::EnterDensity) {
    return enteringStepCost(densityWeight(qb, base), len);
  } else if constexpr (K == CostKernel::EnterUniform) {
    return enteringStepCost(1.0f, len);
  } else if constexpr (K == CostKernel::TrapezoidDensity) {
    return trapezoidStepCost(densityWeight(qa, base), densityWeight(qb, base), len);
  } else if constexpr (K == CostKernel::EdgeGradient) {
    const float diff = densityFromByte(qb) - densityFromByte(qa);
    return enteringStepCost(base + absf_portable(diff), len);
  } else {
    const float rise = densityFromByte(qb) - densityFromByte(qa);
    return enteringStepCost(base + (rise > 0.0f ? rise : 0.0f), len);
  }
}

// Length of the step from the previous-plane neighbour n[dc][db] (db along the plane's B axis, dc
// along C; [1][1] is straight behind).
AT_FORCE_INLINE float neighbourLength(int dc, int db, SweepLengths l) {
  return dc == 1 ? (db == 1 ? l.straight : l.alongB) : (db == 1 ? l.alongC : l.diagonal);
}

// Update of one voxel (current value cur, density byte qb) from its 9 neighbours nb[dc][db] in the
// previous plane (densities qn, read only by kernels that need them): the sweeps' per-voxel
// arithmetic on every backend. Out-of-grid neighbours are +infinity.
template <CostKernel K>
AT_FORCE_INLINE float relaxVoxel(float cur, const float nb[3][3], const std::uint8_t qn[3][3], std::uint8_t qb,
                                 SweepLengths l, float base) {
  if constexpr (K == CostKernel::EnterDensity) {
    return enteringUpdate(cur, nb, densityWeight(qb, base), l);
  } else if constexpr (K == CostKernel::EnterUniform) {
    return enteringUpdate(cur, nb, 1.0f, l);
  } else {
    float best = cur;
    AT_UNROLL for (int dc = 0; dc < 3; ++dc)
      AT_UNROLL for (int db = 0; db < 3; ++db)
        best = minf(best, nb[dc][db] + stepCost<K>(qn[dc][db], qb, neighbourLength(dc, db, l), base));
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

// Calls f.template operator()<K>() with the kernel k names: the one switch from a run-time kernel
// to the compile-time one every backend's loops are instantiated for.
template <class F>
decltype(auto) withCostKernel(CostKernel k, F&& f) {
  switch (k) {
    case CostKernel::EnterUniform: return f.template operator()<CostKernel::EnterUniform>();
    case CostKernel::TrapezoidDensity: return f.template operator()<CostKernel::TrapezoidDensity>();
    case CostKernel::EdgeGradient: return f.template operator()<CostKernel::EdgeGradient>();
    case CostKernel::EdgeAscent: return f.template operator()<CostKernel::EdgeAscent>();
    case CostKernel::EnterDensity: break;
  }
  return f.template operator()<CostKernel::EnterDensity>();
}

}  // namespace at::wdt
