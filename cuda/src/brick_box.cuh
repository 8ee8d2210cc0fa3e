// A brick with its one-voxel halo in shared memory, as the brick rounds use it: the WDT's converge
// mode (brick_solver.cu) and the multi-label growth (label_growth.cu). Layout, the thread that owns
// each plane cell in a sweep, which halo cells each thread loads, and the round queues. Private to
// cuda/src.
#pragma once

#include <cstddef>

#include "brick_solver.h"
#include "wdt/growth_engine.h"

namespace at::cuda {
namespace {

constexpr int kEdge = kBrickEdge;      // brick edge in voxels
constexpr int kSide = kEdge + 2;       // with the halo
constexpr int kStrideY = kSide;        // shared-memory strides of the brick with its halo; the odd
constexpr int kStrideZ = kSide * kSide + 1;  // z stride puts the two z rows a warp reads in an x
constexpr int kCells = kStrideZ * kSide;     // sweep on different banks
constexpr int kThreads = kEdge * kEdge;      // one thread per plane cell

static_assert(kThreads == 256 && kEdge == 16, "the sweep maps the 256 threads onto a 16 × 16 plane");
static_assert(kGrowthBrickEdge == kBrickEdge, "the growth's bricks are the brick solver's");

__host__ __device__ constexpr int cellStride(int axis) { return axis == 0 ? 1 : axis == 1 ? kStrideY : kStrideZ; }
__device__ __forceinline__ int cellIndex(int x, int y, int z) { return (x + 1) + kStrideY * (y + 1) + kStrideZ * (z + 1); }

// The plane cell (ub, uc) thread t owns in a sweep along axis A (plane axes B, C in
// wdt::axisSweepLengths' order), chosen so that a warp's 32 cells (and their neighbours at any one
// offset) fall on 32 different shared-memory banks: 16 b × 2 c in the x sweeps (y stride 18, odd z
// stride), 2 b × 16 c in the z sweeps (x, then y stride 18). The y sweeps (x and z) keep 16 × 2 and
// read with 2-way conflicts; no padding of the two strides avoids them on all axes.
template <int A>
__device__ __forceinline__ void planeCell(int t, int& ub, int& uc) {
  ub = A == 2 ? 2 * (t / 32) + (t & 1) : t & (kEdge - 1);
  uc = A == 2 ? (t & 31) >> 1 : t / kEdge;
}

// The two sweeps (+ then −) along brick axis A over a brick of extent ext: for each plane in sweep
// order, visit(cell, prevCell) on the thread's plane cell (planeCell) if it lies in the brick —
// prevCell is the cell one plane back along the sweep, the centre of its 9 previous-plane
// neighbours (the others at ± cellStride of the plane axes) — then a block barrier. Returns whether
// any of the thread's visits returned true. Every thread of the block must call it.
template <int A, int Unroll, class Visit>
__device__ __forceinline__ bool sweepPlanes(const int ext[3], int t, Visit&& visit) {
  constexpr int BA = A == 0 ? 1 : 0, CA = A == 2 ? 1 : 2;  // plane axes: wdt::axisSweepLengths' order
  constexpr int sa = cellStride(A), sb = cellStride(BA), sc = cellStride(CA);
  int ub, uc;
  planeCell<A>(t, ub, uc);
  const bool valid = ub < ext[BA] && uc < ext[CA];
  const int lateral = (ub + 1) * sb + (uc + 1) * sc;
  bool changed = false;
#pragma unroll
  for (int dir = 1; dir >= -1; dir -= 2) {
#pragma unroll Unroll
    for (int step = 0; step < kEdge; ++step) {
      const int pa = dir > 0 ? step : kEdge - 1 - step;
      if (valid && pa < ext[A]) {
        const int idx = lateral + (pa + 1) * sa;
        if (visit(idx, idx - dir * sa)) changed = true;
      }
      __syncthreads();
    }
  }
  return changed;
}

// Calls load(slot, hx, hy, hz) for the halo cells thread t loads (coordinates relative to the
// brick origin, one of them −1 or kEdge): slots 0 … 5 one cell of each face — x faces, y faces,
// z faces, at (t % 16, t / 16) — and slot 6, for threads 0 … 199, one cell of the halo's 12 edges
// and 8 corners.
template <class Load>
__device__ __forceinline__ void forEachHaloCell(int t, Load&& load) {
  const int tx = t % kEdge, ty = t / kEdge;
#pragma unroll
  for (int side = 0; side < 2; ++side) {
    const int h = side ? kEdge : -1;
    load(side, h, tx, ty);      // x faces
    load(2 + side, tx, h, ty);  // y faces
    load(4 + side, tx, ty, h);  // z faces
  }
  if (t < 12 * kEdge) {  // edge e along axis e / 4, at the corners e % 4 of the other two axes
    const int e = t / kEdge, u = t % kEdge, h1 = (e & 1) ? kEdge : -1, h2 = (e & 2) ? kEdge : -1;
    if (e < 4) load(6, u, h1, h2);
    else if (e < 8) load(6, h1, u, h2);
    else load(6, h1, h2, u);
  } else if (t < 12 * kEdge + 8) {
    const int c = t - 12 * kEdge;
    load(6, (c & 1) ? kEdge : -1, (c & 2) ? kEdge : -1, (c & 4) ? kEdge : -1);
  }
}

// The end of a brick's visit, for every thread of the block: ORs the threads' neighbour masks
// (brickNeighbourMask of the voxels they lowered) into *blockMask (shared, zeroed at the visit's
// start), then calls queue(brick) for each neighbour brick the mask names that lies in the grid
// (bricks per axis `bricks`; `b` this brick's coordinates) and for this brick if `changed`.
template <class Queue>
__device__ __forceinline__ void queueAfterVisit(unsigned mask, bool changed, int t, int brick, const int b[3],
                                                const int bricks[3], unsigned* blockMask, Queue&& queue) {
  mask = __reduce_or_sync(0xffffffffu, mask);
  if ((t & 31) == 0 && mask) atomicOr(blockMask, mask);
  __syncthreads();
  const unsigned all = *blockMask;
  if (t < 27 && ((all >> t) & 1u)) {
    const int nb[3] = {b[0] + t % 3 - 1, b[1] + (t / 3) % 3 - 1, b[2] + t / 9 - 1};
    if (nb[0] >= 0 && nb[0] < bricks[0] && nb[1] >= 0 && nb[1] < bricks[1] && nb[2] >= 0 && nb[2] < bricks[2]) {
      queue(nb[0] + bricks[0] * (nb[1] + bricks[1] * nb[2]));
    }
  }
  // Something decreased: sweep again next round (until a sweep lowers nothing).
  if (changed && t == 0) queue(brick);
}

// Queues `brick` for the round whose list has parity `parity` (its length in counters[counter]),
// once: flags and lists hold 2 × brickCount ints, by parity.
__device__ __forceinline__ void activateBrick(int* flags, int* counters, int* lists, int brickCount, int brick,
                                              int parity, int counter) {
  if (atomicExch(flags + std::size_t(parity) * brickCount + brick, 1) == 0) {
    const int slot = atomicAdd(counters + counter, 1);
    lists[std::size_t(parity) * brickCount + slot] = brick;
  }
}

}  // namespace
}  // namespace at::cuda
