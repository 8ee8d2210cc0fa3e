// The kernels of the CUDA multi-label growth (label_growth.cu): fill, reset of labels, seeds, the
// rounds over bricks (ordered by key, brick-level Δ-stepping) and the read-back. Private to
// cuda/src; included by label_growth.cu only.
#pragma once

#include <cooperative_groups.h>
#include <cuda_runtime.h>

#include <algorithm>
#include <cstdint>

#include "brick_box.cuh"
#include "wdt/brick_neighbours.h"
#include "wdt/step_cost.h"

namespace at::cuda {
namespace {

namespace cg = cooperative_groups;
using wdt::CostKernel;

constexpr std::int32_t kInf = wdt::kGrowthInf;

// The queues of the rounds: flags, lists and keys per round parity (2 × bricks ints each),
// counters [round % 3] of the lists' lengths, the smallest key queued for each round, the visits
// made in each round, and the statistics. A queued brick's key is a lower bound of the distances
// its visit can write: the smallest distance among the voxels whose lowering queued it (0 for
// seeds and reset labels). Keys only order the visits (ordered rounds, solveGrowth); any order
// reaches the same fixed point.
constexpr int kMinKeyCounter = 7;   // [7..9]: smallest key queued for round r, at 7 + r % 3
constexpr int kVisitCounter = 10;   // [10..12]: bricks listed for a visit in round r, at 10 + r % 3
constexpr int kCounters = 13;
constexpr std::int32_t kNoKey = 0x7F7F7F7F;  // above every distance (the scale keeps them < 2^30); memset byte 0x7F

struct Queues {
  int* flags = nullptr;
  int* lists = nullptr;
  int* keys = nullptr;
  int* visitList = nullptr;  // bricks ints: the bricks a round visits (solveGrowth)
  int* counters = nullptr;  // [0..2] list lengths, [3] rounds run, [4] bricks still active,
                            // [5] visits, [6] voxels reset, then kMinKeyCounter, kVisitCounter
  int brickCount = 0;
};

struct GridShape {
  int n[3];       // voxels per axis
  int bricks[3];  // bricks per axis
};

__device__ __forceinline__ int brickOfVoxel(const GridShape& g, int x, int y, int z) {
  return x / kEdge + g.bricks[0] * (y / kEdge + g.bricks[1] * (z / kEdge));
}

// Queues `brick` for the round of list `parity` and counter `counter` with key at most `key`. The
// caller also lowers that round's smallest key to `key` (noteKey), once for many activations.
__device__ __forceinline__ void activate(const Queues& q, int brick, int parity, int counter, int key) {
  atomicMin(q.keys + std::size_t(parity) * q.brickCount + brick, key);
  activateBrick(q.flags, q.counters, q.lists, q.brickCount, brick, parity, counter);
}
__device__ __forceinline__ void noteKey(const Queues& q, int counter, int key) {
  atomicMin(q.counters + kMinKeyCounter + counter, key);
}

__global__ void fillKeys(unsigned long long* keys, std::size_t count, unsigned long long value) {
  for (std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; i < count;
       i += std::size_t(gridDim.x) * blockDim.x)
    keys[i] = value;
}

// Every voxel whose label has its bit set in `reset` (65536 bits) goes back to (+infinity,
// kNoLabel); its brick is queued for round 0.
__global__ void resetLabels(unsigned long long* keys, GridShape g, const unsigned* reset, Queues q) {
  const std::size_t count = std::size_t(g.n[0]) * g.n[1] * g.n[2];
  const unsigned long long none = wdt::packGrowthKey(kInf, wdt::kNoLabel);
  int n = 0;
  for (std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; i < count;
       i += std::size_t(gridDim.x) * blockDim.x) {
    const std::int32_t label = wdt::growthKeyLabel(keys[i]);
    if (label == wdt::kNoLabel || !((reset[label >> 5] >> (label & 31)) & 1u)) continue;
    keys[i] = none;
    ++n;
    const int x = int(i % std::size_t(g.n[0])), y = int((i / std::size_t(g.n[0])) % std::size_t(g.n[1])),
              z = int(i / (std::size_t(g.n[0]) * g.n[1]));
    const int brick = brickOfVoxel(g, x, y, z);
    if (*static_cast<volatile int*>(q.flags + brick) == 0) {
      activate(q, brick, 0, 0, 0);
      noteKey(q, 0, 0);
    }
  }
  if (n) atomicAdd(q.counters + 6, n);
}

// Seeds (voxel index, label) to (0, label); their bricks, and the neighbour bricks whose halo holds
// a seed (one on a brick's face may lower nothing in its own brick), are queued for round 0.
__global__ void writeSeeds(unsigned long long* keys, GridShape g, const unsigned* index, const int* label, int count,
                           Queues q) {
  for (int s = int(blockIdx.x * blockDim.x + threadIdx.x); s < count; s += int(gridDim.x * blockDim.x)) {
    const std::size_t i = index[s];
    keys[i] = wdt::packGrowthKey(0, label[s]);
    const int x = int(i % std::size_t(g.n[0])), y = int((i / std::size_t(g.n[0])) % std::size_t(g.n[1])),
              z = int(i / (std::size_t(g.n[0]) * g.n[1]));
    activate(q, brickOfVoxel(g, x, y, z), 0, 0, 0);
    const unsigned mask = wdt::brickNeighbourMask(x % kEdge, y % kEdge, z % kEdge, kEdge);
    const int b[3] = {x / kEdge, y / kEdge, z / kEdge};
    for (int n = 0; n < 27; ++n) {
      if (!(mask & (1u << n))) continue;
      const int nb[3] = {b[0] + n % 3 - 1, b[1] + (n / 3) % 3 - 1, b[2] + n / 9 - 1};
      if (nb[0] < 0 || nb[1] < 0 || nb[2] < 0 || nb[0] >= g.bricks[0] || nb[1] >= g.bricks[1] || nb[2] >= g.bricks[2])
        continue;
      activate(q, nb[0] + g.bricks[0] * (nb[1] + g.bricks[1] * nb[2]), 0, 0, 0);
    }
    noteKey(q, 0, 0);
  }
}

__global__ void keysToLabels(const unsigned long long* keys, std::uint16_t* out, std::size_t count) {
  for (std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; i < count;
       i += std::size_t(gridDim.x) * blockDim.x) {
    const std::int32_t l = wdt::growthKeyLabel(keys[i]);
    out[i] = l == wdt::kNoLabel ? 0 : std::uint16_t(l);
  }
}

__global__ void keysToDistances(const unsigned long long* keys, float* out, std::size_t count, float scale) {
  for (std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; i < count;
       i += std::size_t(gridDim.x) * blockDim.x) {
    const std::int32_t d = wdt::growthKeyDistance(keys[i]);
    out[i] = d == kInf ? __builtin_huge_valf() : float(d) / scale;
  }
}

// A block's shared memory: the brick and its halo as (distance, label) keys (wdt::packGrowthKey:
// one 64-bit load gives a neighbour's pair) and densities (floats: wdt::densityFromByte), and the
// neighbour mask of the voxels it lowered.
struct GrowthShared {
  unsigned long long key[kCells];
  float f[kCells];
  unsigned mask;
  int lowest;                // the smallest distance the visit lowered a voxel to
};

struct SolveArgs {
  unsigned long long* keys;
  const std::uint8_t* density;
  GridShape g;
  Queues q;
  wdt::SweepLengths lengths[3];  // per sweep axis, plane axes as in wdt::axisSweepLengths
  float base;
  float scale;                   // fixed-point units per unit of cost
  int maxRounds;
  // Ordered rounds (solveGrowth): the first window above the smallest queued key, and the visits a
  // round may make per block before the window halves / below which it doubles. ordered false:
  // every queued brick is visited in every round.
  bool ordered;
  int window0, fewVisits, manyVisits;
};

// The sweep pair (+ then −) along brick axis A with the growth's stencil. Returns whether the
// thread's voxels changed. Every thread of the block must call it (it holds the barriers).
template <CostKernel K, int A>
__device__ __forceinline__ bool sweepAxis(GrowthShared& sh, const int ext[3], int t, const wdt::SweepLengths& len,
                                          float base, float scale) {
  constexpr int sb = cellStride(A == 0 ? 1 : 0), sc = cellStride(A == 2 ? 1 : 2);
  return sweepPlanes<A, 2>(ext, t, [&](int idx, int prev) {
    std::int32_t n[3][3], nl[3][3];
    float fn[3][3];
#pragma unroll
    for (int dc = 0; dc < 3; ++dc)
#pragma unroll
      for (int db = 0; db < 3; ++db) {
        const int i = prev + (dc - 1) * sc + (db - 1) * sb;
        const unsigned long long key = sh.key[i];
        n[dc][db] = wdt::growthKeyDistance(key);
        nl[dc][db] = wdt::growthKeyLabel(key);
        fn[dc][db] = wdt::needsNeighbourDensity(K) ? sh.f[i] : 0.0f;
      }
    const unsigned long long own = sh.key[idx];
    std::int32_t d = wdt::growthKeyDistance(own), l = wdt::growthKeyLabel(own);
    const std::int32_t d0 = d, l0 = l;
    wdt::relaxLabelledVoxel<K>(d, l, n, nl, fn, sh.f[idx], len, base, scale);
    if (d == d0 && l == l0) return false;
    sh.key[idx] = wdt::packGrowthKey(d, l);
    return true;
  });
}

// One halo cell (hx, hy, hz) (relative to the brick origin o; one coordinate −1 or kEdge) into the
// box: its key from the state (+infinity, kNoLabel off the grid) and its density.
__device__ __forceinline__ void loadHalo(const SolveArgs& a, GrowthShared& sh, const int o[3], int hx, int hy, int hz) {
  const int gx = o[0] + hx, gy = o[1] + hy, gz = o[2] + hz;
  const int cell = cellIndex(hx, hy, hz);
  unsigned long long key = wdt::packGrowthKey(kInf, wdt::kNoLabel);
  float f = 0.0f;
  if (gx >= 0 && gx < a.g.n[0] && gy >= 0 && gy < a.g.n[1] && gz >= 0 && gz < a.g.n[2]) {
    const std::size_t i = std::size_t(gx) + std::size_t(a.g.n[0]) * (std::size_t(gy) + std::size_t(a.g.n[1]) * std::size_t(gz));
    key = __ldcg(a.keys + i);
    f = wdt::densityFromByte(__ldg(a.density + i));
  }
  sh.key[cell] = key;
  sh.f[cell] = f;
}

// One block handles one brick for one round.
template <CostKernel K>
__device__ void visitBrick(const SolveArgs& a, int brick, int round, GrowthShared& sh, int t) {
  const int p = round & 1;
  const int* nb = a.g.bricks;
  const int b[3] = {brick % nb[0], (brick / nb[0]) % nb[1], brick / (nb[0] * nb[1])};
  const int o[3] = {b[0] * kEdge, b[1] * kEdge, b[2] * kEdge};
  const int ext[3] = {min(kEdge, a.g.n[0] - o[0]), min(kEdge, a.g.n[1] - o[1]), min(kEdge, a.g.n[2] - o[2])};
  const std::size_t nx = std::size_t(a.g.n[0]), nxy = nx * std::size_t(a.g.n[1]);

  // Thread (tx, ty) loads the brick's column (tx, ty, 0..15), then its halo cells
  // (forEachHaloCell). Keys are read through L2 only: other multiprocessors write them during the
  // kernel.
  if (t == 0) {
    sh.mask = 0;
    sh.lowest = kNoKey;
  }
  const int tx = t % kEdge, ty = t / kEdge;
  const bool column = tx < ext[0] && ty < ext[1];
  const std::size_t g0 = std::size_t(o[0] + tx) + nx * std::size_t(o[1] + ty) + nxy * std::size_t(o[2]);
  unsigned long long k[kEdge];
  std::uint8_t q[kEdge];
#pragma unroll
  for (int z = 0; z < kEdge; ++z) {
    const bool in = column && z < ext[2];
    k[z] = in ? __ldcg(a.keys + g0 + nxy * z) : wdt::packGrowthKey(kInf, wdt::kNoLabel);
    q[z] = in ? __ldg(a.density + g0 + nxy * z) : 0;
  }
#pragma unroll
  for (int z = 0; z < kEdge; ++z) {
    const int cell = cellIndex(tx, ty, z);
    sh.key[cell] = k[z];
    sh.f[cell] = wdt::densityFromByte(q[z]);
  }
  forEachHaloCell(t, [&](int, int hx, int hy, int hz) { loadHalo(a, sh, o, hx, hy, hz); });
  __syncthreads();

  bool changed = sweepAxis<K, 0>(sh, ext, t, a.lengths[0], a.base, a.scale);
  changed |= sweepAxis<K, 1>(sh, ext, t, a.lengths[1], a.base, a.scale);
  changed |= sweepAxis<K, 2>(sh, ext, t, a.lengths[2], a.base, a.scale);
  changed = __syncthreads_or(changed) != 0;

  // The state still holds what this visit loaded (only this brick writes its voxels): store the
  // column's voxels whose key went down, read again rather than kept in registers through the sweeps.
  unsigned mask = 0;
  int lowest = kNoKey;
  if (changed && column) {
    unsigned long long before[kEdge];
#pragma unroll
    for (int z = 0; z < kEdge; ++z) before[z] = z < ext[2] ? __ldcg(a.keys + g0 + nxy * z) : 0ull;
#pragma unroll
    for (int z = 0; z < kEdge; ++z) {
      if (z < ext[2]) {
        const int cell = cellIndex(tx, ty, z);
        const unsigned long long key = sh.key[cell];
        if (key != before[z]) {
          a.keys[g0 + nxy * std::size_t(z)] = key;
          mask |= wdt::brickNeighbourMask(tx, ty, z, kEdge);
          lowest = min(lowest, wdt::growthKeyDistance(key));
        }
      }
    }
  }
  lowest = __reduce_min_sync(0xffffffffu, lowest);
  if ((t & 31) == 0 && lowest < kNoKey) atomicMin(&sh.lowest, lowest);
  const int next = (round + 1) % 3;
  // queueAfterVisit's barrier orders the block's minimum before its reads here.
  queueAfterVisit(mask, changed, t, brick, b, nb, &sh.mask, [&](int n) { activate(a.q, n, 1 - p, next, sh.lowest); });
  if (t == 0 && sh.lowest < kNoKey) noteKey(a.q, next, sh.lowest);
  __syncthreads();  // shared memory is the next visit's
}

// Round r reads list r % 2 (length in counter r % 3), queues for round r + 1 into list (r + 1) % 2
// (counter (r + 1) % 3) and zeroes counter (r + 2) % 3, which every block read before the last
// barrier (brick_solver.cu's protocol).
//
// Ordered rounds (a.ordered): a round visits only the queued bricks whose key lies within a window
// above the round's smallest key, and queues the others again for the next round with their keys
// (brick-level Δ-stepping): the front is worked from the seeds outwards, so fewer bricks are
// visited with distances that a cheaper path lowers again later. A round has two phases: all
// threads of the grid sort the list's bricks into this round's visit list and the next round's
// list; after a grid barrier, block b visits entries b, b + G, b + 2G … of the visit list (G
// blocks), so the visits spread evenly over the blocks. The window doubles after a round that
// listed fewer than fewVisits visits a block and halves after one of more than manyVisits; every
// block computes it from the same count, read after the barrier.
template <CostKernel K>
__global__ void __launch_bounds__(kThreads) solveGrowth(SolveArgs a) {
  extern __shared__ unsigned char shared[];
  GrowthShared& sh = *reinterpret_cast<GrowthShared*>(shared);
  const int t = int(threadIdx.x);
  cg::grid_group grid = cg::this_grid();
  int round = 0, active = 0, visits = 0;
  long long window = a.window0;
  const int G = int(gridDim.x);
  for (;; ++round) {
    active = __ldcg(a.q.counters + round % 3);
    if (active == 0 || round == a.maxRounds) break;
    const int p = round & 1, next = (round + 1) % 3;
    int* keys = a.q.keys + std::size_t(p) * a.q.brickCount;
    int* flags = a.q.flags + std::size_t(p) * a.q.brickCount;
    const int* list = a.q.lists + std::size_t(p) * a.q.brickCount;
    const long long limit =
        a.ordered ? (long long)__ldcg(a.q.counters + kMinKeyCounter + round % 3) + window : (long long)kNoKey;
    for (int first = int(blockIdx.x) * kThreads; first < active; first += G * kThreads) {
      const int j = first + t;
      int carried = kNoKey, brick = 0;
      bool visit = false;
      if (j < active) {
        brick = __ldcg(list + j);
        const int key = __ldcg(keys + brick);
        flags[brick] = 0;  // may be queued again in round + 2
        keys[brick] = kNoKey;
        if (key <= limit) {
          visit = true;
        } else {
          activate(a.q, brick, 1 - p, next, key);
          carried = key;
        }
      }
      // One atomic a warp for the visit list's slots and one for the next round's smallest key.
      const unsigned listing = __ballot_sync(0xffffffffu, visit);
      int slot = 0;
      if ((t & 31) == 0 && listing) slot = atomicAdd(a.q.counters + kVisitCounter + round % 3, __popc(listing));
      slot = __shfl_sync(0xffffffffu, slot, 0) + __popc(listing & ((1u << (t & 31)) - 1u));
      if (visit) a.q.visitList[slot] = brick;
      carried = __reduce_min_sync(0xffffffffu, carried);
      if ((t & 31) == 0 && carried < kNoKey) noteKey(a.q, next, carried);
    }
    grid.sync();
    const int listed = __ldcg(a.q.counters + kVisitCounter + round % 3);
    for (int j = int(blockIdx.x); j < listed; j += G) {
      visitBrick<K>(a, __ldcg(a.q.visitList + j), round, sh, t);
      ++visits;
    }
    if (listed < a.fewVisits * G) window = min(window * 2, (long long)kNoKey);
    else if (listed > a.manyVisits * G && window > 1) window /= 2;
    if (blockIdx.x == 0 && t == 0) {  // counters every block read in round − 1
      a.q.counters[(round + 2) % 3] = 0;
      a.q.counters[kMinKeyCounter + (round + 2) % 3] = kNoKey;
      a.q.counters[kVisitCounter + (round + 2) % 3] = 0;
    }
    grid.sync();
  }
  if (t == 0 && visits) atomicAdd(a.q.counters + 5, visits);
  if (blockIdx.x == 0 && t == 0) {
    a.q.counters[3] = round;
    a.q.counters[4] = active;
  }
}

unsigned gridBlocks(std::size_t count) {
  const std::size_t blocks = (count + 255) / 256;
  return unsigned(std::min<std::size_t>(std::max<std::size_t>(blocks, 1), 16384));
}

}  // namespace
}  // namespace at::cuda
