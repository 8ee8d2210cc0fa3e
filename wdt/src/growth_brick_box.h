// The CPU growth engine's brick box (label_growth_cpu.cpp): a 16³ brick and its one-voxel halo in
// local arrays, which rows a visit's sweeps must relax, and the local passes of sweeps over the box
// (growth_brick_box.cpp, with an AVX2 clone). Internal to at_wdt.
#pragma once

#include <cstdint>
#include <cstring>

#include "wdt/growth_engine.h"
#include "wdt/stencil.h"
#include "wdt/step_cost.h"

#define AT_ALWAYS_INLINE inline __attribute__((always_inline))

namespace at::growth_cpu {

constexpr int E = kGrowthBrickEdge;
constexpr int S = E + 2;  // a box edge: the brick and its halo
constexpr int kCells = S * S * S;
constexpr std::int32_t kInf = wdt::kGrowthInf;
using Dist = std::int32_t;  // fixed-point distance (wdt/step_cost.h)

// A brick with its halo: distances d, labels l and densities f (densityFromByte: kept as floats, so
// that the sweeps convert no bytes). Layout N: x fastest, cell x + S·(y + S·z) for box coordinates 0 … S − 1
// (0 and S − 1 are the halo); layout T (the x sweeps): y fastest, cell y + S·(x + S·z). Cells off
// the grid hold (+infinity, kNoLabel) and are never swept.
struct BrickBox {
  alignas(64) Dist d[kCells];
  alignas(64) std::int32_t l[kCells];
  alignas(64) float f[kCells];
  alignas(64) Dist dT[kCells];
  alignas(64) std::int32_t lT[kCells];
  alignas(64) float fT[kCells];
  int ext[3] = {E, E, E};  // voxels of the brick inside the grid, per axis
};

// Which rows a sweep must relax. A sweep along axis A relaxes each voxel from its 9 neighbours in
// the previous plane, so a row needs it again only if a voxel of the three previous-plane rows next
// to it decreased since the row was last relaxed in that direction. The sweeps walk two families of
// lines: lines along x (the y and z sweeps' rows, indexed [z][y]) and lines along y (the x sweeps'
// rows in layout T, indexed [z][x]). `lineX`, `lineY` hold the clock time of the last change of any
// voxel of a line, `swept` the time each row was last relaxed, per sweep direction. A visit starts
// with every halo line marked changed, and every interior line too unless the brick's interior is
// known to be settled (its last visit ended with a pass that changed nothing, and no reset or seed
// touched it since). Changes of an x-halo voxel are marked in the lines along y only: every step
// from it moves along x, and the x sweeps cover those steps (likewise for the y halo).
struct RowStamps {
  int lineX[S][S];
  int lineY[S][S];
  int swept[6][S][S];  // [sweep axis · 2 + (direction < 0)][a][c]
  int clock = 1;

  void start(const int ext[3], bool settled) {
    for (int z = 0; z < S; ++z)
      for (int u = 0; u < S; ++u) {
        const bool haloZ = z == 0 || z > ext[2];
        lineX[z][u] = settled && !(haloZ || u == 0 || u > ext[1]) ? 0 : 1;
        lineY[z][u] = settled && !(haloZ || u == 0 || u > ext[0]) ? 0 : 1;
      }
    std::memset(swept, 0, sizeof swept);
    clock = 1;
  }
};

// t[y + S·(x + S·z)] = s[x + S·(y + S·z)] (the same map takes T back to N).
template <class T>
AT_ALWAYS_INLINE void transposeBox(const T* __restrict s, T* __restrict t) {
  for (int z = 0; z < S; ++z)
    for (int y = 0; y < S; ++y)
      for (int x = 0; x < S; ++x) t[y + S * (x + S * z)] = s[x + S * (y + S * z)];
}

// Local passes of y± and z± (layout N) and x± (layout T, transposed only when an x sweep has rows
// to relax) over `box` until a pass changes nothing or 16 passes ran; returns whether the last pass
// still changed something. `settled`: the brick's interior is known settled (RowStamps).
using RelaxBoxFn = bool (*)(BrickBox&, RowStamps&, bool, const wdt::SweepLengths[3], float, float);

// The local passes for cost kernel `k`, compiled for AVX2 when `avx2` (the CPU has it).
RelaxBoxFn relaxBoxFunction(wdt::CostKernel k, bool avx2);

}  // namespace at::growth_cpu
