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
// (½(1 + 1)·len = len), so both map to EnterUniform. Gradient and ascent costs belong to the
// step a → b, not to a voxel, and are physical: base·len for the travel plus the intensity change
// |f(b) − f(a)| (ascent: only a rise) not scaled by the step length — a path's intensity part is
// the total change of f along it, so crossing an edge costs its contrast once at 0.1 mm or 1 mm
// voxels and along an axis or a diagonal, while travel costs base per mm.
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

// Cost of the step a → b of length `len` from the two voxels' densities fa = densityFromByte(qa)
// and fb (engines that keep densities as floats pass them; the byte form below converts first, so
// both give the same float).
template <CostKernel K>
AT_FORCE_INLINE float stepCostFromDensity(float fa, float fb, float len, float base) {
  if constexpr (K == CostKernel::EnterDensity) {
    return enteringStepCost(base + fb, len);
  } else if constexpr (K == CostKernel::EnterUniform) {
    return enteringStepCost(1.0f, len);
  } else if constexpr (K == CostKernel::TrapezoidDensity) {
    return trapezoidStepCost(base + fa, base + fb, len);
  } else if constexpr (K == CostKernel::EdgeGradient) {
    return base * len + absf_portable(fb - fa);
  } else {
    const float rise = fb - fa;
    return base * len + (rise > 0.0f ? rise : 0.0f);
  }
}

// Cost of the step a → b (density bytes qa, qb) of length `len`. (densityWeight(q, base) is
// base + densityFromByte(q): the same float as above.)
template <CostKernel K>
AT_FORCE_INLINE float stepCost(std::uint8_t qa, std::uint8_t qb, float len, float base) {
  return stepCostFromDensity<K>(densityFromByte(qa), densityFromByte(qb), len, base);
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

// ─── Multi-label growth (label_growth.h) ───
// Every voxel carries a distance and the label of the seed it is reached from. Pairs are ordered
// lexicographically: the smaller distance wins, and among equal distances the smaller label value
// — the documented tie rule of the growth.
//
// The growth's distances are fixed-point integers: each step costs the WDT's step cost (above)
// times `scale`, rounded to the nearest integer (at least 1), and costs add exactly. With float
// sums a tie could depend on the order of the relaxations — two paths whose costs differ can round
// to the same sum at one voxel, and which label reaches it first would decide — so the sweeps, the
// GPU's rounds and Dijkstra could disagree on labels. Exact sums make every order end at the same
// fixed point: D(v) the smallest path cost, L(v) the smallest label with a path of that cost.
// The front end picks `scale` so that no distance reaches kGrowthInf (label_growth.cpp).
constexpr std::int32_t kGrowthInf = 0x7FFFFFFF;  // not reached (yet)
// kNoLabel marks voxels no seed has reached; it loses every tie. Labels are ints (values 0..65535
// and kNoLabel), so that vector units compare them with their signed compares.
constexpr std::int32_t kNoLabel = 0x7FFFFFFF;

// The density a growth engine gives a voxel that growth may not enter (outside the params' range
// limit, label_growth.h): every step into or out of it costs kGrowthInf, so no label reaches it
// through growth and none passes through it.
constexpr float kBlockedDensity = -1.0f;

// The fixed-point cost of the step a → b (densities fa, fb as in stepCostFromDensity, or
// kBlockedDensity: then kGrowthInf).
template <CostKernel K>
AT_FORCE_INLINE std::int32_t growthStepCost(float fa, float fb, float len, float base, float scale) {
  if (fa < 0.0f || fb < 0.0f) return kGrowthInf;
  const std::int32_t c = std::int32_t(stepCostFromDensity<K>(fa, fb, len, base) * scale + 0.5f);
  return c < 1 ? 1 : c;
}

// d + cost, staying at kGrowthInf for d = kGrowthInf (no overflow: finite distances stay far below).
AT_FORCE_INLINE std::int32_t addGrowthCost(std::int32_t d, std::int32_t cost) {
  const std::int32_t capped = kGrowthInf - cost;
  return (d < capped ? d : capped) + cost;
}

// The growth's update of one voxel (distance d, label l, density fb) from its 9 neighbours in the
// previous plane: distances nb, labels nl, densities fn (densityFromByte of the bytes; read only by
// kernels that need them). The voxel keeps the smallest (distance, label) pair among its own and
// the candidates (nb + growthStepCost, nl): the smallest distance first, then the smallest label
// among the pairs that reach it (the lexicographic minimum in fewer vector operations).
template <CostKernel K>
AT_FORCE_INLINE void relaxLabelledVoxel(std::int32_t& d, std::int32_t& l, const std::int32_t nb[3][3],
                                        const std::int32_t nl[3][3], const float fn[3][3], float fb, SweepLengths len,
                                        float base, float scale) {
  std::int32_t c[3][3];
  std::int32_t best = d;
  AT_UNROLL for (int dc = 0; dc < 3; ++dc)
    AT_UNROLL for (int db = 0; db < 3; ++db) {
      c[dc][db] = addGrowthCost(nb[dc][db], growthStepCost<K>(fn[dc][db], fb, neighbourLength(dc, db, len), base, scale));
      best = c[dc][db] < best ? c[dc][db] : best;
    }
  std::int32_t label = d == best ? l : kNoLabel;
  AT_UNROLL for (int dc = 0; dc < 3; ++dc)
    AT_UNROLL for (int db = 0; db < 3; ++db) {
      // A candidate at +infinity (a blocked step, or an unreached neighbour) carries no label.
      const std::int32_t candidate = c[dc][db] == best && best != kGrowthInf ? nl[dc][db] : kNoLabel;
      label = candidate < label ? candidate : label;
    }
  d = best;
  l = label;
}

// A (distance, label) pair packed into one 64-bit key, distance above label: keys order like the
// pairs, and one 64-bit load or store moves a consistent pair (the growth engines rely on that when
// threads or blocks read voxels another one is writing).
AT_FORCE_INLINE std::uint64_t packGrowthKey(std::int32_t d, std::int32_t l) {
  return (std::uint64_t(std::uint32_t(d)) << 32) | std::uint32_t(l);
}
AT_FORCE_INLINE std::int32_t growthKeyDistance(std::uint64_t key) { return std::int32_t(std::uint32_t(key >> 32)); }
AT_FORCE_INLINE std::int32_t growthKeyLabel(std::uint64_t key) { return std::int32_t(std::uint32_t(key)); }

// Bounds on the cost per mm of a step of a kernel, for grids whose shortest step is
// `shortestStepMm`: every step a → b of length len costs at least lo·len and at most hi·len (the
// edge kernels' intensity part, at most 1 per step, is at most 1/shortestStepMm per mm). The exact
// reference sizes its buckets and the growth its fixed-point scale from them.
inline void weightRange(CostKernel k, float base, float shortestStepMm, float& lo, float& hi) {
  if (k == CostKernel::EnterUniform) {
    lo = hi = 1.0f;
  } else if (k == CostKernel::EdgeGradient || k == CostKernel::EdgeAscent) {
    lo = base;
    hi = base + 1.0f / shortestStepMm;
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
