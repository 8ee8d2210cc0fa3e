// Converge mode on the GPU: brick rounds that finish a field after a few whole-volume passes.
//
// A whole-volume pass is 6 × (planes) dependent plane steps (1,536 at 256³), so a converged field
// costs passes × that chain, and the last pass only confirms that nothing changes, while after a
// few passes only small parts of the field still change. Here the grid is cut into bricks of 8³
// voxels; a start kernel queues the bricks that can still change, then one cooperative kernel runs
// rounds separated by grid-wide barriers; in each round every active brick is handled by one warp, which loads the brick and a
// one-voxel halo into shared memory, sweeps it x+ x− y+ y− z+ z− (the same 9-neighbour plane
// updates and float operations as the whole-volume sweeps) until a local pass changes nothing,
// writes the voxels that decreased, and activates the bricks whose halo holds a boundary voxel
// that decreased. Work then follows the front: bricks far from it cost nothing.
//
// Result: the fixed point of the step costs, D(v) = min over the 26 neighbours u of D(u) + c(u→v),
// which is the minimum over all paths of the same float sums. Any order of relaxations that ends
// only when no relaxation lowers a value reaches that one fixed point, so the field equals the
// converged sweeps and the exact reference bit for bit (tests/cuda compares them).
//
// Deterministic round by round: a brick's own voxels are written only by the warp handling that
// brick, and halos are read from a snapshot of the boundary voxels (shell[round % 2]) that nobody
// writes during the round; decreased boundary voxels go to the other snapshot. A snapshot can be
// older than the field for voxels that changed two rounds ago, never newer: the brick that reads
// them read the fresh value in the round after the change (the change activated it), and values
// only decrease, so an older, larger halo value can no longer lower anything. Which warp handles
// which brick varies between runs; what each brick computes does not.
#include "brick_solver.h"

#include <cooperative_groups.h>

#include <string>

#include "cuda_util.h"
#include "sweep_rules.cuh"

namespace at::cuda {
namespace {

namespace cg = cooperative_groups;

constexpr int kBrick = 8;                             // brick edge in voxels
constexpr int kSide = kBrick + 2;                     // with the halo
constexpr int kCells = kSide * kSide * kSide;         // shared-memory cells per brick
constexpr int kWarps = 8, kThreads = 32 * kWarps;     // one brick per warp at a time
constexpr int kLocalPassCap = 4;                      // local passes per visit before re-queueing
constexpr int kInteriorPerLane = kBrick * kBrick * kBrick / 32;

__host__ __device__ constexpr int cellStride(int axis) { return axis == 0 ? 1 : axis == 1 ? kSide : kSide * kSide; }
__device__ __forceinline__ int cellIndex(int x, int y, int z) { return (x + 1) + kSide * ((y + 1) + kSide * (z + 1)); }

struct SolveArgs {
  BrickSolveBuffers buf;
  int n[3];       // grid voxels per axis
  int bricks[3];  // bricks per axis
  int brickCount;
  wdt::SweepLengths lengths[3];  // per sweep axis, plane axes as in wdt::axisSweepLengths
  float len27[27];               // the same lengths by offset (dx + 1) + 3·(dy + 1) + 9·(dz + 1)
  float base;
  int maxRounds;
};

// Bits (dx + 1) + 3·(dy + 1) + 9·(dz + 1) of the neighbour bricks whose halo holds the brick's
// voxel (x, y, z): one per face, edge and corner the voxel lies on.
__device__ __forceinline__ unsigned neighbourMask(int x, int y, int z) {
  const int e[3] = {x == 0 ? -1 : (x == kBrick - 1 ? 1 : 0), y == 0 ? -1 : (y == kBrick - 1 ? 1 : 0),
                    z == 0 ? -1 : (z == kBrick - 1 ? 1 : 0)};
  unsigned mask = 0;
#pragma unroll
  for (int s = 1; s < 8; ++s) {  // non-empty subsets of the axes
    const int dx = (s & 1) ? e[0] : 0, dy = (s & 2) ? e[1] : 0, dz = (s & 4) ? e[2] : 0;
    if (((s & 1) && !e[0]) || ((s & 2) && !e[1]) || ((s & 4) && !e[2])) continue;
    mask |= 1u << ((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1));
  }
  return mask;
}

// Queues `brick` for the round whose list has parity `parity`, once.
__device__ __forceinline__ void activate(const SolveArgs& a, int brick, int parity, int counter) {
  if (atomicExch(a.buf.flags + std::size_t(parity) * a.brickCount + brick, 1) == 0) {
    const int slot = atomicAdd(a.buf.counters + counter, 1);
    a.buf.lists[std::size_t(parity) * a.brickCount + slot] = brick;
  }
}

// One directional sweep pair (+ then −) along brick axis A over the brick in shared memory. Lane
// owns plane cells (ub, uc) and (ub, uc + 4). Returns whether any of the lane's voxels decreased.
template <StepRule R, WeightRule W, int A>
__device__ __forceinline__ bool sweepAxis(float* s, const std::uint8_t* sq, const int ext[3], int lane,
                                          const wdt::SweepLengths& l, float base) {
  constexpr bool kQn = kNeedsNeighbourDensity<R, W>;
  constexpr int BA = A == 0 ? 1 : 0, CA = A == 2 ? 1 : 2;  // plane axes: wdt::axisSweepLengths' order
  constexpr int sa = cellStride(A), sb = cellStride(BA), sc = cellStride(CA);
  const int ub = lane & 7, uc = lane >> 3;
  const bool valid[2] = {ub < ext[BA] && uc < ext[CA], ub < ext[BA] && uc + 4 < ext[CA]};
  const int lateral[2] = {(ub + 1) * sb + (uc + 1) * sc, (ub + 1) * sb + (uc + 5) * sc};
  bool changed = false;
#pragma unroll
  for (int dir = 1; dir >= -1; dir -= 2) {
#pragma unroll
    for (int step = 0; step < kBrick; ++step) {
      const int pa = dir > 0 ? step : kBrick - 1 - step;
      if (pa < ext[A]) {
#pragma unroll
        for (int k = 0; k < 2; ++k) {
          if (valid[k]) {
            const int idx = lateral[k] + (pa + 1) * sa;
            const int prev = idx - dir * sa;
            float n[3][3];
            std::uint8_t qn[3][3];
            gatherNeighbours<kQn>(s, sq, prev, sb, sc, n, qn);
            const float cur = s[idx];
            const float v = relax<R, W>(cur, n, qn, sq[idx], l, base);
            if (v < cur) {
              s[idx] = v;
              changed = true;
            }
          }
        }
      }
      __syncwarp();
    }
  }
  return changed;
}

// One warp handles one brick for one round (see the file comment).
template <StepRule R, WeightRule W>
__device__ void visitBrick(const SolveArgs& a, int brick, int round, float* s, std::uint8_t* sq, int lane) {
  const int p = round & 1;
  const int b[3] = {brick % a.bricks[0], (brick / a.bricks[0]) % a.bricks[1], brick / (a.bricks[0] * a.bricks[1])};
  const int o[3] = {b[0] * kBrick, b[1] * kBrick, b[2] * kBrick};
  const int ext[3] = {min(kBrick, a.n[0] - o[0]), min(kBrick, a.n[1] - o[1]), min(kBrick, a.n[2] - o[2])};
  const std::size_t nx = std::size_t(a.n[0]), nxy = nx * std::size_t(a.n[1]);
  const float* shellIn = a.buf.shell[p];
  float* shellOut = a.buf.shell[1 - p];

  // Brick voxels from the field, halo voxels from this round's snapshot, +infinity off the grid.
  // Read through L2 only: other multiprocessors wrote them in earlier rounds of this kernel.
#pragma unroll 8
  for (int c = lane; c < kCells; c += 32) {
    const int hx = c % kSide - 1, hy = (c / kSide) % kSide - 1, hz = c / (kSide * kSide) - 1;
    const int gx = o[0] + hx, gy = o[1] + hy, gz = o[2] + hz;
    float v = kInf;
    std::uint8_t q = 0;
    if (gx >= 0 && gx < a.n[0] && gy >= 0 && gy < a.n[1] && gz >= 0 && gz < a.n[2]) {
      const std::size_t g = std::size_t(gx) + nx * std::size_t(gy) + nxy * std::size_t(gz);
      const bool own = unsigned(hx) < unsigned(kBrick) && unsigned(hy) < unsigned(kBrick) && unsigned(hz) < unsigned(kBrick);
      v = __ldcg((own ? a.buf.field : shellIn) + g);
      q = __ldg(a.buf.density + g);
    }
    s[c] = v;
    sq[c] = q;
  }
  __syncwarp();
  float before[kInteriorPerLane];  // the lane's brick voxels i = lane + 32k as loaded
#pragma unroll
  for (int k = 0; k < kInteriorPerLane; ++k) {
    const int i = lane + 32 * k;
    before[k] = s[cellIndex(i & 7, (i >> 3) & 7, i >> 6)];
  }

  bool changedLast = true;
  for (int pass = 0; pass < kLocalPassCap && changedLast; ++pass) {
    bool changed = sweepAxis<R, W, 0>(s, sq, ext, lane, a.lengths[0], a.base);
    changed |= sweepAxis<R, W, 1>(s, sq, ext, lane, a.lengths[1], a.base);
    changed |= sweepAxis<R, W, 2>(s, sq, ext, lane, a.lengths[2], a.base);
    changedLast = __any_sync(0xffffffffu, changed);
  }

  unsigned mask = 0;
#pragma unroll
  for (int k = 0; k < kInteriorPerLane; ++k) {
    const int i = lane + 32 * k, x = i & 7, y = (i >> 3) & 7, z = i >> 6;
    if (x < ext[0] && y < ext[1] && z < ext[2]) {
      const float v = s[cellIndex(x, y, z)];
      if (v < before[k]) {
        const std::size_t g = std::size_t(o[0] + x) + nx * std::size_t(o[1] + y) + nxy * std::size_t(o[2] + z);
        a.buf.field[g] = v;
        const unsigned m = neighbourMask(x, y, z);
        if (m) {
          shellOut[g] = v;
          mask |= m;
        }
      }
    }
  }
  mask = __reduce_or_sync(0xffffffffu, mask);
  const int next = (round + 1) % 3;
  if (lane < 27 && ((mask >> lane) & 1u)) {
    const int nb[3] = {b[0] + lane % 3 - 1, b[1] + (lane / 3) % 3 - 1, b[2] + lane / 9 - 1};
    if (nb[0] >= 0 && nb[0] < a.bricks[0] && nb[1] >= 0 && nb[1] < a.bricks[1] && nb[2] >= 0 && nb[2] < a.bricks[2]) {
      activate(a, nb[0] + a.bricks[0] * (nb[1] + a.bricks[1] * nb[2]), 1 - p, next);
    }
  }
  // Not settled within the cap: handle it again next round (its halo is unchanged or fresher).
  if (changedLast && lane == 0) activate(a, brick, 1 - p, next);
  __syncwarp();  // the shared memory is the next visit's
}

// Round r reads list r % 2 (counter r % 3), queues for round r + 1 into list (r + 1) % 2 (counter
// (r + 1) % 3) and zeroes counter (r + 2) % 3, which every block read before the last barrier.
template <StepRule R, WeightRule W>
__global__ void __launch_bounds__(kThreads) solveBricks(SolveArgs a) {
  __shared__ float sD[kWarps][kCells];
  __shared__ std::uint8_t sQ[kWarps][kCells];
  const int warp = int(threadIdx.x) >> 5, lane = int(threadIdx.x) & 31;
  const int worker = int(blockIdx.x) * kWarps + warp, workers = int(gridDim.x) * kWarps;
  cg::grid_group grid = cg::this_grid();
  int round = 0, active = 0;
  for (;; ++round) {
    active = __ldcg(a.buf.counters + round % 3);
    if (active == 0 || round == a.maxRounds) break;
    const int p = round & 1;
    for (int j = worker; j < active; j += workers) {
      const int brick = __ldcg(a.buf.lists + std::size_t(p) * a.brickCount + j);
      if (lane == 0) a.buf.flags[std::size_t(p) * a.brickCount + brick] = 0;  // may be queued again in round + 2
      visitBrick<R, W>(a, brick, round, sD[warp], sQ[warp], lane);
    }
    if (blockIdx.x == 0 && threadIdx.x == 0) a.buf.counters[(round + 2) % 3] = 0;
    grid.sync();
  }
  if (blockIdx.x == 0 && threadIdx.x == 0) {
    a.buf.result[0] = round;
    a.buf.result[1] = active;
  }
}

// Start of the rounds from any field that is at or above the fixed point (the initial field, or
// one after whole-volume passes): both snapshots become copies of the field, and every brick that
// holds a voxel some neighbour can still lower (the same step costs and float operations as the
// sweeps) is queued for round 0.
template <StepRule R, WeightRule W>
__global__ void startBricks(SolveArgs a) {
  const std::size_t nx = std::size_t(a.n[0]), nxy = nx * std::size_t(a.n[1]), count = nxy * std::size_t(a.n[2]);
  for (std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; i < count;
       i += std::size_t(gridDim.x) * blockDim.x) {
    const float v = a.buf.field[i];
    a.buf.shell[0][i] = v;
    a.buf.shell[1][i] = v;
    const int x = int(i % nx), y = int((i / nx) % std::size_t(a.n[1])), z = int(i / nxy);
    const std::uint8_t qb = a.buf.density[i];
    float best = v;
    for (int dz = -1; dz <= 1; ++dz) {
      if (z + dz < 0 || z + dz >= a.n[2]) continue;
      for (int dy = -1; dy <= 1; ++dy) {
        if (y + dy < 0 || y + dy >= a.n[1]) continue;
        for (int dx = -1; dx <= 1; ++dx) {
          if ((dx | dy | dz) == 0 || x + dx < 0 || x + dx >= a.n[0]) continue;
          const std::size_t j = std::size_t(x + dx) + nx * std::size_t(y + dy) + nxy * std::size_t(z + dz);
          const float len = a.len27[(dx + 1) + 3 * (dy + 1) + 9 * (dz + 1)];
          best = wdt::minf(best, a.buf.field[j] + stepCost<R, W>(a.buf.density[j], qb, len, a.base));
        }
      }
    }
    if (best < v) {
      const int brick = x / kBrick + a.bricks[0] * (y / kBrick + a.bricks[1] * (z / kBrick));
      // Many voxels share a brick: look before taking the atomic.
      if (*static_cast<volatile int*>(a.buf.flags + brick) == 0) activate(a, brick, 0, 0);
    }
  }
}

SolveArgs makeArgs(const BrickSolveBuffers& b, int nx, int ny, int nz) {
  SolveArgs a{};
  a.buf = b;
  a.n[0] = nx, a.n[1] = ny, a.n[2] = nz;
  a.bricks[0] = (nx + kBrick - 1) / kBrick, a.bricks[1] = (ny + kBrick - 1) / kBrick,
  a.bricks[2] = (nz + kBrick - 1) / kBrick;
  a.brickCount = int(brickCount(nx, ny, nz));
  return a;
}

template <StepRule R, WeightRule W>
Status launchSolve(const SolveArgs& a, cudaStream_t stream) {
  const std::size_t count = std::size_t(a.n[0]) * a.n[1] * a.n[2];
  if (count == 0) return {};
  AT_TRY(check(cudaMemsetAsync(a.buf.flags, 0, 2 * std::size_t(a.brickCount) * sizeof(int), stream), "cudaMemsetAsync(brick flags)"));
  AT_TRY(check(cudaMemsetAsync(a.buf.counters, 0, 3 * sizeof(int), stream), "cudaMemsetAsync(brick counters)"));
  const std::size_t startBlocks = (count + 255) / 256;
  startBricks<R, W><<<unsigned(startBlocks < 8192 ? startBlocks : 8192), 256, 0, stream>>>(a);
  AT_TRY(check(cudaGetLastError(), "launch of the brick start kernel"));

  auto* kernel = solveBricks<R, W>;
  int device = 0, sms = 0, perSm = 0;
  AT_TRY(check(cudaGetDevice(&device), "cudaGetDevice"));
  AT_TRY(check(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device), "cudaDeviceGetAttribute(SM count)"));
  AT_TRY(check(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&perSm, kernel, kThreads, 0), "cudaOccupancyMaxActiveBlocksPerMultiprocessor(brick solver)"));
  if (perSm < 1) return fail("WDT CUDA backend: the brick solver's blocks do not fit on a multiprocessor");
  // Every block must be resident for the grid barrier; no more blocks than the bricks can use.
  const int needed = (a.brickCount + kWarps - 1) / kWarps;
  const int blocks = needed < perSm * sms ? needed : perSm * sms;
  SolveArgs args = a;
  void* params[] = {&args};
  return check(cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(kernel), dim3(unsigned(blocks)),
                                           dim3(kThreads), params, 0, stream),
               "cudaLaunchCooperativeKernel(brick solver)");
}

}  // namespace

std::size_t brickCount(int nx, int ny, int nz) {
  return std::size_t((nx + kBrick - 1) / kBrick) * std::size_t((ny + kBrick - 1) / kBrick) *
         std::size_t((nz + kBrick - 1) / kBrick);
}

Status launchBrickSolve(const BrickSolveBuffers& b, int nx, int ny, int nz, const BrickSolveParams& params,
                        cudaStream_t stream) {
  SolveArgs a = makeArgs(b, nx, ny, nz);
  const float sx = params.spacing[0], sy = params.spacing[1], sz = params.spacing[2];
  for (int axis = 0; axis < 3; ++axis) a.lengths[axis] = wdt::axisSweepLengths(axis, sx, sy, sz);
  const wdt::SweepLengths lx = a.lengths[0], ly = a.lengths[1], lz = a.lengths[2];
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int axes = (dx != 0) + (dy != 0) + (dz != 0);
        float len = 0;
        if (axes == 3) len = lx.diagonal;
        else if (axes == 1) len = dx ? lx.straight : dy ? ly.straight : lz.straight;
        else if (axes == 2) len = !dz ? lx.alongB : !dy ? lx.alongC : ly.alongC;
        a.len27[(dx + 1) + 3 * (dy + 1) + 9 * (dz + 1)] = len;
      }
  a.base = params.baseCost;
  a.maxRounds = params.maxRounds;
  return launchForRule(params.rule, params.weight, [&]<StepRule R, WeightRule W>() { return launchSolve<R, W>(a, stream); });
}

}  // namespace at::cuda
