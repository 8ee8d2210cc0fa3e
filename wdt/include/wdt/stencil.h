// The per-voxel arithmetic of the weighted distance transform, written once for every backend:
// the CPU sweeps, the CUDA kernels and the exact Dijkstra reference all call these functions, so
// that the same inputs give the same float operations in the same order (results can then be
// compared bit for bit where the visiting order is the same).
//
// Usable from C++ and CUDA: functions are AT_HOST_DEVICE, take plain values, use no std:: calls.
#pragma once

#include <cstdint>

#if defined(__CUDACC__)
#define AT_HOST_DEVICE __host__ __device__
#else
#define AT_HOST_DEVICE
#endif

namespace at::wdt {

// Density of a voxel: HU windowed to 0..1 and quantised to 8 bits (0..255). Both backends use the
// quantised value, which keeps the GPU's weight volume at one byte per voxel.
AT_HOST_DEVICE inline std::uint8_t densityByte(float hu, float huMin, float huMax) {
  float d = (hu - huMin) / (huMax - huMin);
  d = d < 0.0f ? 0.0f : (d > 1.0f ? 1.0f : d);
  return static_cast<std::uint8_t>(d * 255.0f + 0.5f);
}

AT_HOST_DEVICE inline float densityFromByte(std::uint8_t q) { return float(q) * (1.0f / 255.0f); }

// Density weight rule: w = base + density.
AT_HOST_DEVICE inline float densityWeight(std::uint8_t q, float base) { return base + densityFromByte(q); }

// Physical step lengths (mm) of a sweep along axis `a` whose planes span axes `b` and `c`:
// straight (0,0), one lateral step along b (1,0), along c (0,1), and both (1,1).
struct SweepLengths {
  float straight, alongB, alongC, diagonal;
};

AT_HOST_DEVICE inline float sqrtf_portable(float x) {
#if defined(__CUDA_ARCH__)
  return ::sqrtf(x);
#else
  return __builtin_sqrtf(x);
#endif
}

AT_HOST_DEVICE inline SweepLengths sweepLengths(float spacingA, float spacingB, float spacingC) {
  return {spacingA, sqrtf_portable(spacingA * spacingA + spacingB * spacingB),
          sqrtf_portable(spacingA * spacingA + spacingC * spacingC),
          sqrtf_portable(spacingA * spacingA + spacingB * spacingB + spacingC * spacingC)};
}

// Lengths of a sweep along grid axis `axis` (0 = i, 1 = j, 2 = k) with the plane axes in the order
// every backend uses: i → (b = j, c = k), j → (b = i, c = k), k → (b = i, c = j). Unlike calling
// sweepLengths per axis, the diagonal is summed in one canonical order (sx² + sy²) + sz² for every
// axis, so each of the 26 steps has exactly one float length whichever sweep takes it — the exact
// reference (Dijkstra) uses the same lengths and converged sweeps then equal it bit for bit.
AT_HOST_DEVICE inline SweepLengths axisSweepLengths(int axis, float sx, float sy, float sz) {
  const float xx = sx * sx, yy = sy * sy, zz = sz * sz;
  const float diagonal = sqrtf_portable((xx + yy) + zz);
  if (axis == 0) return {sx, sqrtf_portable(xx + yy), sqrtf_portable(xx + zz), diagonal};
  if (axis == 1) return {sy, sqrtf_portable(xx + yy), sqrtf_portable(yy + zz), diagonal};
  return {sz, sqrtf_portable(xx + zz), sqrtf_portable(yy + zz), diagonal};
}

// Length of the step (dx, dy, dz) ∈ {−1, 0, 1}³ \ {0} to one of the 26 neighbours: the length a
// sweep along any axis the step moves in gives it (axisSweepLengths makes them one float).
AT_HOST_DEVICE inline float stepLength(int dx, int dy, int dz, float sx, float sy, float sz) {
  if (dx) {
    const SweepLengths l = axisSweepLengths(0, sx, sy, sz);  // b = y, c = z
    return dy ? (dz ? l.diagonal : l.alongB) : (dz ? l.alongC : l.straight);
  }
  if (dy) {
    const SweepLengths l = axisSweepLengths(1, sx, sy, sz);  // b = x (no step), c = z
    return dz ? l.alongC : l.straight;
  }
  return axisSweepLengths(2, sx, sy, sz).straight;
}

// The smaller of two distances. Distances are never NaN or −0 (sums of +0, positive costs and
// +infinity), so the compare-select and the GPU's min instruction give the same bits; the GPU
// uses its single min instruction (a compare and a select would be two).
AT_HOST_DEVICE inline float minf(float a, float b) {
#if defined(__CUDA_ARCH__)
  return fminf(a, b);
#else
  return a < b ? a : b;
#endif
}

// Entering rule update of one voxel b with weight wb from its 9 neighbours in the previous plane,
// n[dc+1][db+1] (out-of-grid neighbours are +infinity). Groups neighbours by step length first,
// so the cost w(b)·|step| is computed four times, not nine. Returns min(current, best candidate).
AT_HOST_DEVICE inline float enteringUpdate(float current, const float n[3][3], float wb, SweepLengths l) {
  const float m00 = n[1][1];
  const float m10 = minf(n[1][0], n[1][2]);
  const float m01 = minf(n[0][1], n[2][1]);
  const float m11 = minf(minf(n[0][0], n[0][2]), minf(n[2][0], n[2][2]));
  const float c = minf(minf(m00 + wb * l.straight, m10 + wb * l.alongB),
                       minf(m01 + wb * l.alongC, m11 + wb * l.diagonal));
  return minf(current, c);
}

// The cost of one step a → b of physical length `len` under the entering rule.
AT_HOST_DEVICE inline float enteringStepCost(float wb, float len) { return wb * len; }

// The cost of one step a → b under the trapezoid rule: ½(w(a) + w(b))·|step|.
AT_HOST_DEVICE inline float trapezoidStepCost(float wa, float wb, float len) { return 0.5f * (wa + wb) * len; }

}  // namespace at::wdt
