// Converge mode on the GPU: brick rounds that finish a field after a few whole-volume passes (or
// from the seeds alone).
//
// A whole-volume pass is 6 × (planes) dependent plane steps (1,536 at 256³), so a converged field
// costs passes × that chain, and the last pass only confirms that nothing changes, while after a
// few passes only small parts of the field still change. Here the grid is cut into bricks of 16³
// voxels; a start kernel queues the bricks that can still change, then one cooperative kernel runs
// rounds separated by grid-wide barriers. In each round every active brick is handled by one block
// of 256 threads, which loads the brick and a one-voxel halo into shared memory, sweeps it once
// x+ x− y+ y− z+ z− (the same 9-neighbour plane updates and float operations as the whole-volume
// sweeps, one thread per plane cell), writes the voxels that decreased, activates the bricks
// whose halo holds a boundary voxel that decreased, and queues itself again if anything decreased
// (the next visit then also sees its neighbours' newer halo). Work follows the front: bricks far
// from it cost nothing.
//
// Result: the fixed point of the step costs, D(v) = min over the 26 neighbours u of D(u) + c(u→v),
// which is the minimum over all paths of the same float sums. Any order of relaxations that ends
// only when no relaxation lowers a value reaches that one fixed point, so the field equals the
// converged sweeps and the exact reference bit for bit (tests/cuda compares them). A brick leaves
// the lists only after a visit whose sweep lowered nothing; that sweep applied every relaxation
// inside the brick and from its halo, since each of the 26 neighbours of a voxel lies in the
// previous plane of one of the six directional sweeps.
//
// Deterministic round by round: a brick's own voxels are written only by the block handling that
// brick, and halos are read from a snapshot of the boundary voxels (shell[round % 2]) that nobody
// writes during the round; decreased boundary voxels go to the other snapshot. A snapshot can be
// older than the field for voxels that changed two rounds ago, never newer: the brick that reads
// them read the fresh value in the round after the change (the change activated it), and values
// only decrease, so an older, larger halo value can no longer lower anything. Which block handles
// which brick varies between runs; what each brick computes does not.
#include "brick_solver.h"

#include <cooperative_groups.h>

#include <algorithm>

#include "brick_box.cuh"
#include "cuda_util.h"
#include "sweep_rules.cuh"
#include "wdt/brick_neighbours.h"

namespace at::cuda {
namespace {

namespace cg = cooperative_groups;

// Whether the sweeps read each voxel's weight as a float computed once at load time (the entering
// rule with density weights: wdt::densityWeight, the float the per-step update would compute)
// instead of its density byte. Saves three instructions of ~36 per plane step.
template <CostKernel K>
constexpr bool kFloatWeights = K == CostKernel::EnterDensity;

// A block's shared memory: the brick with its halo (distances; weights or density bytes, of the
// brick's own voxels only unless the rule reads neighbours' densities) and the neighbour mask.
template <CostKernel K>
struct BrickShared {
  float d[kCells];
  float w[kFloatWeights<K> ? kCells : 1];
  std::uint8_t q[kFloatWeights<K> ? 1 : kCells];
  unsigned mask;
};

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

// Bits of the neighbour bricks whose halo holds the brick's voxel (x, y, z).
__device__ __forceinline__ unsigned neighbourMask(int x, int y, int z) { return wdt::brickNeighbourMask(x, y, z, kEdge); }

// Queues `brick` for the round whose list has parity `parity`, once.
__device__ __forceinline__ void activate(const SolveArgs& a, int brick, int parity, int counter) {
  activateBrick(a.buf.flags, a.buf.counters, a.buf.lists, a.brickCount, brick, parity, counter);
}

// One directional sweep pair (+ then −) along brick axis A over the brick in shared memory
// (sweepPlanes). Returns whether the thread's voxels decreased. Every thread of the block must call
// it (it holds the block's barriers).
template <CostKernel K, int A>
__device__ __forceinline__ bool sweepAxis(BrickShared<K>& sh, const int ext[3], int t, const wdt::SweepLengths& l,
                                          float base) {
  constexpr bool kQn = wdt::needsNeighbourDensity(K);
  constexpr int sb = cellStride(A == 0 ? 1 : 0), sc = cellStride(A == 2 ? 1 : 2);
  return sweepPlanes<A, 4>(ext, t, [&](int idx, int prev) {
    float n[3][3];
    std::uint8_t qn[3][3];
    gatherNeighbours<kQn>(sh.d, sh.q, prev, sb, sc, n, qn);
    const float cur = sh.d[idx];
    float v;
    if constexpr (kFloatWeights<K>) v = wdt::enteringUpdate(cur, n, sh.w[idx], l);
    else v = wdt::relaxVoxel<K>(cur, n, qn, sh.q[idx], l, base);
    if (!(v < cur)) return false;
    sh.d[idx] = v;
    return true;
  });
}

// One halo voxel (hx, hy, hz) of the brick at origin o (coordinates relative to o, one of them
// −1 or kEdge): its snapshot value (+infinity off the grid), its density byte if the rule reads
// neighbours' densities, and its shared-memory cell.
struct HaloVoxel {
  float d;
  std::uint8_t q;
  int cell;
};

template <bool kQn>
__device__ __forceinline__ HaloVoxel loadHalo(const SolveArgs& a, const float* shellIn, const int o[3], int hx, int hy,
                                              int hz) {
  const int gx = o[0] + hx, gy = o[1] + hy, gz = o[2] + hz;
  HaloVoxel h{kInf, 0, cellIndex(hx, hy, hz)};
  if (gx >= 0 && gx < a.n[0] && gy >= 0 && gy < a.n[1] && gz >= 0 && gz < a.n[2]) {
    const std::size_t g = std::size_t(gx) + std::size_t(a.n[0]) * (std::size_t(gy) + std::size_t(a.n[1]) * std::size_t(gz));
    h.d = __ldcg(shellIn + g);
    if constexpr (kQn) h.q = __ldg(a.buf.density + g);
  }
  return h;
}

// One block handles one brick for one round (see the file comment).
template <CostKernel K>
__device__ void visitBrick(const SolveArgs& a, int brick, int round, BrickShared<K>& sh, int t) {
  constexpr bool kQn = wdt::needsNeighbourDensity(K);
  const int p = round & 1;
  const int b[3] = {brick % a.bricks[0], (brick / a.bricks[0]) % a.bricks[1], brick / (a.bricks[0] * a.bricks[1])};
  const int o[3] = {b[0] * kEdge, b[1] * kEdge, b[2] * kEdge};
  const int ext[3] = {min(kEdge, a.n[0] - o[0]), min(kEdge, a.n[1] - o[1]), min(kEdge, a.n[2] - o[2])};
  const std::size_t nx = std::size_t(a.n[0]), nxy = nx * std::size_t(a.n[1]);
  const float* shellIn = a.buf.shell[p];
  float* shellOut = a.buf.shell[1 - p];

  // Brick voxels from the field, halo voxels from this round's snapshot, +infinity off the grid.
  // Read through L2 only: other multiprocessors wrote them in earlier rounds of this kernel.
  // Thread (tx, ty) loads the brick's column (tx, ty, 0..15), one voxel of each of the six halo
  // faces and (threads 0..199) one voxel of the halo's edges and corners. The column's loads are
  // all issued before its first store, then the halo's: two memory round trips a visit.
  if (t == 0) sh.mask = 0;
  const int tx = t % kEdge, ty = t / kEdge;
  const bool column = tx < ext[0] && ty < ext[1];
  const std::size_t g0 = std::size_t(o[0] + tx) + nx * std::size_t(o[1] + ty) + nxy * std::size_t(o[2]);
  float d[kEdge];
  std::uint8_t q[kEdge];
#pragma unroll
  for (int z = 0; z < kEdge; ++z) {
    const bool in = column && z < ext[2];
    d[z] = in ? __ldcg(a.buf.field + g0 + nxy * z) : kInf;
    q[z] = in ? __ldg(a.buf.density + g0 + nxy * z) : 0;
  }
#pragma unroll
  for (int z = 0; z < kEdge; ++z) {
    const int cell = cellIndex(tx, ty, z);
    sh.d[cell] = d[z];
    if constexpr (kFloatWeights<K>) sh.w[cell] = wdt::densityWeight(q[z], a.base);
    else sh.q[cell] = q[z];
  }
  HaloVoxel halo[7];
#pragma unroll
  for (int side = 0; side < 2; ++side) {
    const int h = side ? kEdge : -1;
    halo[side] = loadHalo<kQn>(a, shellIn, o, h, tx, ty);      // x faces
    halo[2 + side] = loadHalo<kQn>(a, shellIn, o, tx, h, ty);  // y faces
    halo[4 + side] = loadHalo<kQn>(a, shellIn, o, tx, ty, h);  // z faces
  }
  halo[6].cell = -1;
  if (t < 12 * kEdge) {  // edge e along axis e / 4, at the corners e % 4 of the other two axes
    const int e = t / kEdge, u = t % kEdge, h1 = (e & 1) ? kEdge : -1, h2 = (e & 2) ? kEdge : -1;
    halo[6] = e < 4 ? loadHalo<kQn>(a, shellIn, o, u, h1, h2)
                    : e < 8 ? loadHalo<kQn>(a, shellIn, o, h1, u, h2) : loadHalo<kQn>(a, shellIn, o, h1, h2, u);
  } else if (t < 12 * kEdge + 8) {
    const int c = t - 12 * kEdge;
    halo[6] = loadHalo<kQn>(a, shellIn, o, (c & 1) ? kEdge : -1, (c & 2) ? kEdge : -1, (c & 4) ? kEdge : -1);
  }
#pragma unroll
  for (int k = 0; k < 7; ++k) {
    if (halo[k].cell >= 0) {
      sh.d[halo[k].cell] = halo[k].d;
      if constexpr (kQn) sh.q[halo[k].cell] = halo[k].q;
    }
  }
  __syncthreads();

  bool changed = sweepAxis<K, 0>(sh, ext, t, a.lengths[0], a.base);
  changed |= sweepAxis<K, 1>(sh, ext, t, a.lengths[1], a.base);
  changed |= sweepAxis<K, 2>(sh, ext, t, a.lengths[2], a.base);
  changed = __syncthreads_or(changed) != 0;

  // Voxels of the thread's column that decreased. The field still holds the values this visit
  // loaded (only this brick writes them), so compare against it instead of keeping 16 values per
  // thread in registers through the sweeps.
  unsigned mask = 0;
  if (changed && column) {
    float before[kEdge];
#pragma unroll
    for (int z = 0; z < kEdge; ++z) before[z] = z < ext[2] ? __ldcg(a.buf.field + g0 + nxy * z) : 0.0f;
#pragma unroll
    for (int z = 0; z < kEdge; ++z) {
      if (z < ext[2]) {
        const float v = sh.d[cellIndex(tx, ty, z)];
        if (v < before[z]) {
          const std::size_t g = g0 + nxy * std::size_t(z);
          a.buf.field[g] = v;
          const unsigned m = neighbourMask(tx, ty, z);
          if (m) {
            shellOut[g] = v;
            mask |= m;
          }
        }
      }
    }
  }
  const int next = (round + 1) % 3;
  queueAfterVisit(mask, changed, t, brick, b, a.bricks, &sh.mask, [&](int n) { activate(a, n, 1 - p, next); });
  __syncthreads();  // shared memory is the next visit's
}

// Round r reads list r % 2 (counter r % 3), queues for round r + 1 into list (r + 1) % 2 (counter
// (r + 1) % 3) and zeroes counter (r + 2) % 3, which every block read before the last barrier.
template <CostKernel K>
__global__ void __launch_bounds__(kThreads, 4) solveBricks(SolveArgs a) {
  __shared__ BrickShared<K> sh;
  const int t = int(threadIdx.x);
  cg::grid_group grid = cg::this_grid();
  int round = 0, active = 0;
  for (;; ++round) {
    active = __ldcg(a.buf.counters + round % 3);
    if (active == 0 || round == a.maxRounds) break;
    const int p = round & 1;
    for (int j = int(blockIdx.x); j < active; j += int(gridDim.x)) {
      const int brick = __ldcg(a.buf.lists + std::size_t(p) * a.brickCount + j);
      if (t == 0) a.buf.flags[std::size_t(p) * a.brickCount + brick] = 0;  // may be queued again in round + 2
      visitBrick<K>(a, brick, round, sh, t);
    }
    if (blockIdx.x == 0 && t == 0) a.buf.counters[(round + 2) % 3] = 0;
    grid.sync();
  }
  if (blockIdx.x == 0 && t == 0) {
    a.buf.result[0] = round;
    a.buf.result[1] = active;
  }
}

// Start of the rounds from any field at or above the fixed point (the initial field, or one after
// whole-volume passes). Both snapshots get the field's brick-boundary voxels (the only ones a halo
// reads), and every brick holding a voxel that some neighbour can still lower (the same step
// costs and float operations as the sweeps) is queued for round 0. Each finite voxel u looks at
// its 26 neighbours v and queues v's brick if D(u) + c(u→v) < D(v); an infinite voxel lowers
// nothing, so a field of seeds alone costs one read per voxel. Thread (x, y) of a 32 × 8 tile walks
// kStartZ planes; the field is read through the read-only cache (nothing writes it here).
constexpr int kStartZ = 8;

template <CostKernel K>
__global__ void __launch_bounds__(256) startBricks(SolveArgs a) {
  const int x = int(blockIdx.x) * 32 + int(threadIdx.x), y = int(blockIdx.y) * 8 + int(threadIdx.y);
  if (x >= a.n[0] || y >= a.n[1]) return;
  const std::size_t nx = std::size_t(a.n[0]), nxy = nx * std::size_t(a.n[1]);
  const int z0 = int(blockIdx.z) * kStartZ, z1 = min(z0 + kStartZ, a.n[2]);
  const bool edgeXY = x % kEdge == 0 || x % kEdge == kEdge - 1 || y % kEdge == 0 || y % kEdge == kEdge - 1;
  for (int z = z0; z < z1; ++z) {
    const std::size_t i = std::size_t(x) + nx * std::size_t(y) + nxy * std::size_t(z);
    const float u = __ldg(a.buf.field + i);
    if (edgeXY || z % kEdge == 0 || z % kEdge == kEdge - 1) {
      a.buf.shell[0][i] = u;
      a.buf.shell[1][i] = u;
    }
    if (!(u < kInf)) continue;
    const std::uint8_t qa = wdt::needsNeighbourDensity(K) ? __ldg(a.buf.density + i) : 0;
#pragma unroll
    for (int dz = -1; dz <= 1; ++dz) {
      if (z + dz < 0 || z + dz >= a.n[2]) continue;
#pragma unroll
      for (int dy = -1; dy <= 1; ++dy) {
        if (y + dy < 0 || y + dy >= a.n[1]) continue;
#pragma unroll
        for (int dx = -1; dx <= 1; ++dx) {
          if ((dx | dy | dz) == 0 || x + dx < 0 || x + dx >= a.n[0]) continue;
          const std::size_t j = i + std::ptrdiff_t(dx) + std::ptrdiff_t(dy) * std::ptrdiff_t(nx) + std::ptrdiff_t(dz) * std::ptrdiff_t(nxy);
          const float len = a.len27[(dx + 1) + 3 * (dy + 1) + 9 * (dz + 1)];
          if (u + wdt::stepCost<K>(qa, __ldg(a.buf.density + j), len, a.base) < __ldg(a.buf.field + j)) {
            const int brick = (x + dx) / kEdge + a.bricks[0] * ((y + dy) / kEdge + a.bricks[1] * ((z + dz) / kEdge));
            // Many voxels share a brick: look before taking the atomic.
            if (*static_cast<volatile int*>(a.buf.flags + brick) == 0) activate(a, brick, 0, 0);
          }
        }
      }
    }
  }
}

SolveArgs makeArgs(const BrickSolveBuffers& b, int nx, int ny, int nz) {
  SolveArgs a{};
  a.buf = b;
  a.n[0] = nx, a.n[1] = ny, a.n[2] = nz;
  a.bricks[0] = (nx + kEdge - 1) / kEdge, a.bricks[1] = (ny + kEdge - 1) / kEdge, a.bricks[2] = (nz + kEdge - 1) / kEdge;
  a.brickCount = a.bricks[0] * a.bricks[1] * a.bricks[2];
  return a;
}

template <CostKernel K>
Status launchSolve(const SolveArgs& a, cudaStream_t stream) {
  const std::size_t count = std::size_t(a.n[0]) * a.n[1] * a.n[2];
  if (count == 0) return {};
  AT_TRY(check(cudaMemsetAsync(a.buf.flags, 0, 2 * std::size_t(a.brickCount) * sizeof(int), stream), "cudaMemsetAsync(brick flags)"));
  AT_TRY(check(cudaMemsetAsync(a.buf.counters, 0, 3 * sizeof(int), stream), "cudaMemsetAsync(brick counters)"));
  const dim3 startGrid(unsigned((a.n[0] + 31) / 32), unsigned((a.n[1] + 7) / 8), unsigned((a.n[2] + kStartZ - 1) / kStartZ));
  startBricks<K><<<startGrid, dim3(32, 8), 0, stream>>>(a);
  AT_TRY(check(cudaGetLastError(), "launch of the brick start kernel"));

  auto* kernel = solveBricks<K>;
  // Every block must be resident for the grid barrier: at most the blocks that fit on the device
  // (device 0, the only one the backend uses; asked once), and no more than there are bricks.
  static const Result<int> resident = [kernel]() -> Result<int> {
    int device = 0, sms = 0, perSm = 0;
    AT_TRY(check(cudaGetDevice(&device), "cudaGetDevice"));
    AT_TRY(check(cudaDeviceGetAttribute(&sms, cudaDevAttrMultiProcessorCount, device), "cudaDeviceGetAttribute(SM count)"));
    AT_TRY(check(cudaOccupancyMaxActiveBlocksPerMultiprocessor(&perSm, kernel, kThreads, 0),
                 "cudaOccupancyMaxActiveBlocksPerMultiprocessor(brick solver)"));
    if (perSm < 1) return fail("WDT CUDA backend: the brick solver's blocks do not fit on a multiprocessor");
    return perSm * sms;
  }();
  if (!resident) return tl::unexpected(resident.error());
  const int blocks = std::min(a.brickCount, *resident);
  SolveArgs args = a;
  void* params[] = {&args};
  return check(cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(kernel), dim3(unsigned(blocks)),
                                           dim3(kThreads), params, 0, stream),
               "cudaLaunchCooperativeKernel(brick solver)");
}

}  // namespace

std::size_t brickCount(int nx, int ny, int nz) {
  return std::size_t((nx + kEdge - 1) / kEdge) * std::size_t((ny + kEdge - 1) / kEdge) *
         std::size_t((nz + kEdge - 1) / kEdge);
}

Status launchBrickSolve(const BrickSolveBuffers& b, int nx, int ny, int nz, const BrickSolveParams& params,
                        cudaStream_t stream) {
  SolveArgs a = makeArgs(b, nx, ny, nz);
  const float sx = params.spacing[0], sy = params.spacing[1], sz = params.spacing[2];
  for (int axis = 0; axis < 3; ++axis) a.lengths[axis] = wdt::axisSweepLengths(axis, sx, sy, sz);
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        a.len27[(dx + 1) + 3 * (dy + 1) + 9 * (dz + 1)] = wdt::stepLength(dx, dy, dz, sx, sy, sz);
  a.base = params.baseCost;
  a.maxRounds = params.maxRounds;
  return launchForRule(params.rule, params.weight, [&]<CostKernel K>() { return launchSolve<K>(a, stream); });
}

}  // namespace at::cuda
