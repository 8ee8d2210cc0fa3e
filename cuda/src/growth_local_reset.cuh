// The CUDA growth's local reset (wdt/growth_engine.h, GrowthChange::removedSeeds): the voxels whose
// pair came from removed seeds, found on the old pairs by the CPU engine's rule, then reset. Private
// to cuda/src; included by label_growth.cu after label_growth_kernels.cuh.
//
//   found: the removed seeds' voxels, then each neighbour v of a found voxel u with u's label and
//   D(v) = D(u) + cost(u → v) (wdt::growthStepCost of u's and v's densities over the step's
//   wdt::stepLength, summed by wdt::addGrowthCost: the sums are exact, so the test is too).
//
// A set closed under that step does not depend on the order voxels are found in, so the breadth-
// first levels below (one cooperative kernel, a grid barrier between levels) find exactly the set
// the CPU engine's queue finds on the same pairs. No key is written until the search has ended.
#pragma once

#include <cooperative_groups.h>
#include <cuda_runtime.h>

#include <cstdint>

#include "wdt/stencil.h"
#include "wdt/step_cost.h"

namespace at::cuda {
namespace {

// found: one bit a voxel, zero before a search; list: room for every voxel (each is listed once,
// when its bit is set); count: the list's length.
struct FoundVoxels {
  unsigned* found = nullptr;
  unsigned* list = nullptr;
  unsigned* count = nullptr;
};

__device__ __forceinline__ void markFound(const FoundVoxels& f, unsigned v) {
  const unsigned bit = 1u << (v & 31);
  if (__ldcg(f.found + (v >> 5)) & bit) return;
  if (!(atomicOr(f.found + (v >> 5), bit) & bit)) f.list[atomicAdd(f.count, 1u)] = v;
}

__global__ void markRemovedSeeds(const unsigned* index, int count, FoundVoxels f) {
  for (int s = int(blockIdx.x * blockDim.x + threadIdx.x); s < count; s += int(gridDim.x * blockDim.x))
    markFound(f, index[s]);
}

// Cooperative launch: every block resident. The levels are list ranges [head, tail): all threads
// read the tail before the barrier that opens a level's expansion, and appends happen only between
// that barrier and the next, so every thread sees the same ranges.
template <CostKernel K>
__global__ void findGrownFromRemoved(const unsigned long long* keys, const std::uint8_t* density, GridShape g,
                                     float sx, float sy, float sz, float base, float scale, FoundVoxels f) {
  __shared__ float len[27];
  if (threadIdx.x < 27) {
    const int n = int(threadIdx.x);
    len[n] = n == 13 ? 0.0f : wdt::stepLength(n % 3 - 1, (n / 3) % 3 - 1, n / 9 - 1, sx, sy, sz);
  }
  __syncthreads();
  cooperative_groups::grid_group grid = cooperative_groups::this_grid();
  const std::size_t nx = std::size_t(g.n[0]), nxy = nx * std::size_t(g.n[1]);
  // One warp a listed voxel, lanes 0 … 25 its 26 neighbours: a level then waits for about three
  // loads in a row (u's key, v's key, the bit), not 26 times that.
  const unsigned lane = threadIdx.x & 31u;
  const unsigned warp = (blockIdx.x * blockDim.x + threadIdx.x) >> 5, warps = (gridDim.x * blockDim.x) >> 5;
  const int n = int(lane < 13 ? lane : lane + 1);
  const int dx = n % 3 - 1, dy = (n / 3) % 3 - 1, dz = n / 9 - 1;
  unsigned head = 0;
  for (;;) {
    const unsigned tail = __ldcg(f.count);
    grid.sync();
    if (head == tail) break;
    for (unsigned i = head + warp; lane < 26 && i < tail; i += warps) {
      const unsigned u = __ldcg(f.list + i);
      const int x = int(u % nx), y = int((u / nx) % std::size_t(g.n[1])), z = int(u / nxy);
      if (x + dx < 0 || y + dy < 0 || z + dz < 0 || x + dx >= g.n[0] || y + dy >= g.n[1] || z + dz >= g.n[2]) continue;
      const unsigned v = unsigned(std::int64_t(u) + dx + std::int64_t(nx) * dy + std::int64_t(nxy) * dz);
      const unsigned long long ku = keys[u], kv = keys[v];
      const std::int32_t du = wdt::growthKeyDistance(ku), lu = wdt::growthKeyLabel(ku);
      if (du == kInf || lu == wdt::kNoLabel || wdt::growthKeyLabel(kv) != lu) continue;
      if (__ldcg(f.found + (v >> 5)) & (1u << (v & 31))) continue;
      const std::int32_t cost =
          wdt::growthStepCost<K>(wdt::densityFromByte(density[u]), wdt::densityFromByte(density[v]), len[n], base, scale);
      if (cost == kInf || wdt::addGrowthCost(du, cost) != wdt::growthKeyDistance(kv)) continue;
      markFound(f, v);
    }
    grid.sync();
    head = tail;
  }
}

// Every found voxel to (+infinity, kNoLabel), its brick queued for round 0 with key 0 (regrown from
// its surroundings), as resetLabels does; the count goes to the voxels-reset counter.
__global__ void resetFound(unsigned long long* keys, GridShape g, FoundVoxels f, Queues q) {
  const unsigned long long none = wdt::packGrowthKey(kInf, wdt::kNoLabel);
  const unsigned count = __ldcg(f.count);
  for (unsigned i = blockIdx.x * blockDim.x + threadIdx.x; i < count; i += gridDim.x * blockDim.x) {
    const unsigned v = f.list[i];
    keys[v] = none;
    const int x = int(v % unsigned(g.n[0])), y = int((v / unsigned(g.n[0])) % unsigned(g.n[1])),
              z = int(v / (unsigned(g.n[0]) * unsigned(g.n[1])));
    const int brick = brickOfVoxel(g, x, y, z);
    if (*static_cast<volatile int*>(q.flags + brick) == 0) {
      activate(q, brick, 0, 0, 0);
      noteKey(q, 0, 0);
    }
  }
  if (blockIdx.x == 0 && threadIdx.x == 0) atomicAdd(q.counters + 6, int(count));
}

}  // namespace
}  // namespace at::cuda
