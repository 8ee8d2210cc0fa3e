// The sweep kernels: one launch per sweep, equal to a serial sweep bit for bit.
//
// A sweep along axis a must visit its planes in order (plane p reads plane p∓1 after that plane's
// update), and one plane's update reaches one voxel further sideways per plane (a 45° cone). The
// planes are cut into groups of K and the lanes into TU × TV tiles; a work item is one group of one
// tile. An item computes its K planes in shared memory over the tile plus a halo that shrinks by
// one voxel per plane (K − 1 at the first plane, 0 at the last): exactly the cone the tile's
// results depend on. The halo voxels are recomputed redundantly from the same inputs, so they
// equal what the neighbouring tiles compute.
//
// Inputs of item (group g, tile t): the field before the sweep (`src`, never written during the
// sweep) for the planes' old values, the densities, and the final values of the plane before the
// group over the tile plus a K-voxel ring, which items (g − 1, t') of t and its 8 neighbours
// wrote to `dst`. Each tile has a progress counter (groups completed) in global memory, published
// with a release store after the item's writes; item (g, t) waits with acquire loads until the
// counters of t and its neighbours reach g, then reads that plane. Every read is of data that is
// complete and that nobody writes afterwards in the sweep, so the result is deterministic and
// identical to the CPU backend's serial sweep (same stencil, same order of float operations, no
// FMA contraction: --fmad=false).
//
// Scheduling: one launch per sweep, a grid of as many blocks as fit on the device at once, each
// taking items from a global ticket counter in (group, tile) order. An item only waits for items
// with smaller tickets, which were taken by blocks already running; so the smallest unfinished
// item can always proceed and the sweep cannot deadlock, whatever the number of resident blocks.
// A block fetches its next ticket while it computes, and issues its loads of `src` and densities
// (which depend on no other item) before it waits.
//
// Layout: lanes (u, v) and planes a have arbitrary strides, so x sweeps run on the x-contiguous
// field directly (u = y, v = z): an item's K planes of one lane are K consecutive floats. The
// item's outputs are staged in shared memory and written at its end in the order that is
// contiguous in memory (u-major for y and z sweeps, plane-major for x sweeps).
#include <cuda_runtime.h>

#include <algorithm>
#include <string>

#include <cuda_pipeline_primitives.h>

#include "cuda_util.h"
#include "sweep_kernels.h"
#include "sweep_rules.cuh"

namespace at::cuda {
namespace {

// Tile shape (TU × TV lanes, u contiguous in shared memory), planes per item K, block size.
template <int K_, int TU_, int TV_, int Threads_, int MinBlocks_>
struct Shape {
  static constexpr int K = K_, TU = TU_, TV = TV_, Threads = Threads_, MinBlocks = MinBlocks_;
  static constexpr int RU = TU + 2 * K, RV = TV + 2 * K, RN = RU * RV;  // region: tile + K ring
  static constexpr int Cells = RN / Threads;                           // region cells per thread
  static_assert(RN % Threads == 0, "each thread owns the same number of region cells");
  static_assert(K <= TU && K <= TV, "the ring of the plane before the group lies in the 8 neighbouring tiles");
  static constexpr int Out = K * TU * TV;
  // Shared memory: two distance planes (previous, current), K staged output planes, the K planes'
  // old values, K + 1 density planes (slot 0: the plane before the group; slots 1..K: its planes).
  static constexpr std::size_t Bytes = std::size_t(2 * RN + Out + K * RN) * sizeof(float) + std::size_t(K + 1) * RN;
};
// 8 planes over 32×16-lane tiles: 1536 region cells, 3 per thread; two blocks per multiprocessor,
// so that one block's loads and waits overlap the other's plane steps.
using S8 = Shape<8, 32, 16, 512, 2>;

struct SweepParams {
  const float* src;
  float* dst;
  const std::uint8_t* q;
  int nu, nv, na;
  long long strideU, strideV, strideA;
  int direction;
  wdt::SweepLengths lengths;  // B = u, C = v
  float base;
  int tilesU, tilesV, groups;
  unsigned* sync;             // [0]: ticket counter; [1 + t]: groups completed by tile t
  int* changed;
};

__device__ __forceinline__ unsigned loadAcquire(const unsigned* p) {
  unsigned v;
  asm volatile("ld.acquire.gpu.global.u32 %0, [%1];" : "=r"(v) : "l"(p) : "memory");
  return v;
}

__device__ __forceinline__ void storeRelease(unsigned* p, unsigned v) {
  asm volatile("st.release.gpu.global.u32 [%0], %1;" ::"l"(p), "r"(v) : "memory");
}

template <StepRule R, WeightRule W, class S>
__global__ void __launch_bounds__(S::Threads, S::MinBlocks) sweepKernel(SweepParams p) {
  constexpr int K = S::K, TU = S::TU, TV = S::TV, RU = S::RU, RN = S::RN, C = S::Cells;
  constexpr bool kQn = kNeedsNeighbourDensity<R, W>;
  extern __shared__ float smem[];
  float* sD = smem;                                                  // 2 × RN
  float* sOut = sD + 2 * RN;                                         // K × TU·TV
  float* sOld = sOut + S::Out;                                       // K × RN
  std::uint8_t* sQ = reinterpret_cast<std::uint8_t*>(sOld + K * RN);  // (K + 1) × RN
  __shared__ unsigned sTicket;

  const int tid = int(threadIdx.x);
  const int tiles = p.tilesU * p.tilesV;
  const unsigned items = unsigned(p.groups) * unsigned(tiles);
  unsigned* counter = p.sync;
  unsigned* done = p.sync + 1;
  auto planeOffset = [&](int step) {  // step: index in sweep order
    return (p.direction > 0 ? step : p.na - 1 - step) * p.strideA;
  };

  if (tid == 0) sTicket = atomicAdd(counter, 1u);
  __syncthreads();
  unsigned ticket = sTicket;
  bool changed = false;
  while (ticket < items) {
    __syncthreads();  // every thread has read sTicket (and finished the previous item's reads)
    if (tid == 0) sTicket = atomicAdd(counter, 1u);  // the next item, read after the last barrier
    const int g = int(ticket / unsigned(tiles)), t = int(ticket % unsigned(tiles));
    const int tu = t % p.tilesU, tv = t / p.tilesU;
    const int first = g * K, steps = min(K, p.na - first);
    const int u0 = tu * TU - K, v0 = tv * TV - K;  // region origin in lanes

    // Loads that depend on no other item, all in flight at once: old values (asynchronous copies
    // into shared memory) and densities (registers, then shared memory).
    long long lane[C];
    bool inGrid[C];
#pragma unroll
    for (int c = 0; c < C; ++c) {
      const int r = tid + c * S::Threads;
      const int gu = u0 + r % RU, gv = v0 + r / RU;
      inGrid[c] = gu >= 0 && gu < p.nu && gv >= 0 && gv < p.nv;
      lane[c] = inGrid[c] ? gu * p.strideU + gv * p.strideV : 0;
    }
#pragma unroll
    for (int s = 1; s <= K; ++s) {
#pragma unroll
      for (int c = 0; c < C; ++c) {
        float* to = sOld + (s - 1) * RN + tid + c * S::Threads;
        if (inGrid[c] && s <= steps) {
          __pipeline_memcpy_async(to, p.src + lane[c] + planeOffset(first + s - 1), sizeof(float));
        } else {
          *to = kInf;
        }
      }
    }
    __pipeline_commit();
    std::uint8_t qv[K + 1][C];
#pragma unroll
    for (int s = kQn ? 0 : 1; s <= K; ++s) {
#pragma unroll
      for (int c = 0; c < C; ++c) {
        const bool ok = inGrid[c] && s <= steps && first + s - 1 >= 0;
        qv[s][c] = ok ? __ldg(p.q + lane[c] + planeOffset(first + s - 1)) : std::uint8_t(0);
      }
    }
#pragma unroll
    for (int s = kQn ? 0 : 1; s <= K; ++s) {
#pragma unroll
      for (int c = 0; c < C; ++c) sQ[s * RN + tid + c * S::Threads] = qv[s][c];
    }

    // Wait until the plane before the group is final over the region (tiles t and neighbours).
    if (g > 0 && tid < 9) {
      const int nu = tu + tid % 3 - 1, nv = tv + tid / 3 - 1;
      if (nu >= 0 && nu < p.tilesU && nv >= 0 && nv < p.tilesV) {
        const unsigned* flag = done + nv * p.tilesU + nu;
        while (loadAcquire(flag) < unsigned(g)) __nanosleep(32);
      }
    }
    __syncthreads();
#pragma unroll
    for (int c = 0; c < C; ++c) {
      const int r = tid + c * S::Threads;
      // L2 loads (ld.cg): the values were written by other blocks during this launch.
      sD[r] = inGrid[c] && g > 0 ? __ldcg(p.dst + lane[c] + planeOffset(first - 1)) : kInf;
      if (!inGrid[c]) sD[RN + r] = kInf;  // outside the grid both planes stay +infinity
    }
    __pipeline_wait_prior(0);  // this thread's old values (each thread reads only its own)
    __syncthreads();

#pragma unroll
    for (int s = 1; s <= K; ++s) {
      if (s > steps) continue;  // uniform across the block
      const int h = K - s;  // valid halo of this plane
      const float* prev = sD + ((s - 1) & 1) * RN;
      float* cur = sD + (s & 1) * RN;
      const std::uint8_t* qPrev = sQ + (s - 1) * RN;
#pragma unroll
      for (int c = 0; c < C; ++c) {
        const int r = tid + c * S::Threads;
        const int ru = r % RU, rv = r / RU;
        if (!inGrid[c] || ru < K - h || ru >= K + TU + h || rv < K - h || rv >= K + TV + h) continue;
        float n[3][3];
        std::uint8_t qn[3][3];
#pragma unroll
        for (int dc = 0; dc < 3; ++dc) {
#pragma unroll
          for (int db = 0; db < 3; ++db) {
            n[dc][db] = prev[r + (dc - 1) * RU + (db - 1)];
            qn[dc][db] = kQn ? qPrev[r + (dc - 1) * RU + (db - 1)] : 0;
          }
        }
        const float old = sOld[(s - 1) * RN + r];
        const float v = relax<R, W>(old, n, qn, sQ[s * RN + r], p.lengths, p.base);
        cur[r] = v;
        if (ru >= K && ru < K + TU && rv >= K && rv < K + TV) {
          changed |= v < old;
          sOut[(s - 1) * TU * TV + (rv - K) * TU + (ru - K)] = v;
        }
      }
      __syncthreads();
    }

    // Publish the group as soon as its last plane (the only one later items read) is written; the
    // other planes are written after, in the order that is contiguous in memory.
    auto write = [&](int s, int lu, int lv) {
      const int gu = tu * TU + lu, gv = tv * TV + lv;
      if (gu < p.nu && gv < p.nv) {
        __stcg(p.dst + gu * p.strideU + gv * p.strideV + planeOffset(first + s), sOut[s * TU * TV + lv * TU + lu]);
      }
    };
    for (int i = tid; i < TU * TV; i += S::Threads) write(steps - 1, i % TU, i / TU);
    __syncthreads();
    if (tid == 0) {
      __threadfence();
      storeRelease(done + t, unsigned(g + 1));
    }
    const bool planesContiguous = p.strideA == 1;
    for (int i = tid; i < S::Out; i += S::Threads) {
      int s, lu, lv;
      if (planesContiguous) {
        s = i % K, lu = (i / K) % TU, lv = i / (K * TU);
      } else {
        s = i / (TU * TV), lu = i % TU, lv = (i / TU) % TV;
      }
      if (s < steps - 1) write(s, lu, lv);
    }
    ticket = sTicket;
  }
  if (__syncthreads_or(changed) && tid == 0) atomicOr(p.changed, 1);
}

template <StepRule R, WeightRule W>
cudaError_t prepareKernel(int multiprocessors, int& resident) {
  cudaError_t e = cudaFuncSetAttribute(sweepKernel<R, W, S8>, cudaFuncAttributeMaxDynamicSharedMemorySize, int(S8::Bytes));
  int perSm = 0;
  if (e == cudaSuccess) e = cudaOccupancyMaxActiveBlocksPerMultiprocessor(&perSm, sweepKernel<R, W, S8>, S8::Threads, S8::Bytes);
  if (e == cudaSuccess && perSm < 1) return cudaErrorInvalidConfiguration;
  const int blocks = perSm * multiprocessors;
  resident = resident == 0 ? blocks : std::min(resident, blocks);
  return e;
}

struct Prepared {
  cudaError_t error = cudaSuccess;
  int resident = 0;  // blocks that fit on the device at once (the least over the kernels)
};

const Prepared& prepared() {
  static const Prepared state = [] {
    Prepared s;
    int device = 0, multiprocessors = 0;
    cudaError_t& e = s.error;
    e = cudaGetDevice(&device);
    if (e == cudaSuccess) e = cudaDeviceGetAttribute(&multiprocessors, cudaDevAttrMultiProcessorCount, device);
    if (e == cudaSuccess) e = prepareKernel<StepRule::Trapezoid, WeightRule::Density>(multiprocessors, s.resident);
    if (e == cudaSuccess) e = prepareKernel<StepRule::Entering, WeightRule::Density>(multiprocessors, s.resident);
    if (e == cudaSuccess) e = prepareKernel<StepRule::Entering, WeightRule::Uniform>(multiprocessors, s.resident);
    if (e == cudaSuccess) e = prepareKernel<StepRule::Entering, WeightRule::Gradient>(multiprocessors, s.resident);
    if (e == cudaSuccess) e = prepareKernel<StepRule::Entering, WeightRule::Ascent>(multiprocessors, s.resident);
    return s;
  }();
  return state;
}

template <StepRule R, WeightRule W>
Status launchTyped(const ExactSweepArgs& a, cudaStream_t stream) {
  using S = S8;
  SweepParams p{a.src,     a.dst,       a.density, a.nu, a.nv, a.na, (long long)a.strideU, (long long)a.strideV,
                (long long)a.strideA, a.direction, a.lengths, a.baseCost, (a.nu + S::TU - 1) / S::TU,
                (a.nv + S::TV - 1) / S::TV, (a.na + S::K - 1) / S::K, a.sync, a.changed};
  const long long items = (long long)p.groups * p.tilesU * p.tilesV;
  const int blocks = int(std::min<long long>(items, prepared().resident));
  sweepKernel<R, W, S><<<blocks, S::Threads, S::Bytes, stream>>>(p);
  return check(cudaGetLastError(), "launch of a sweep kernel");
}

__global__ void initDistances(float* d, const std::uint8_t* seeds, std::size_t count) {
  for (std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; i < count;
       i += std::size_t(gridDim.x) * blockDim.x) {
    d[i] = seeds[i] ? 0.0f : kInf;
  }
}

__global__ void fill(float* d, std::size_t count, float value) {
  for (std::size_t i = blockIdx.x * std::size_t(blockDim.x) + threadIdx.x; i < count;
       i += std::size_t(gridDim.x) * blockDim.x) {
    d[i] = value;
  }
}

}  // namespace

Status prepareExactSweeps() {
  return check(prepared().error, "preparing the sweep kernels (shared memory limit, occupancy)");
}

int sweepSyncWords(const ExactSweepArgs& a) {
  return 1 + ((a.nu + S8::TU - 1) / S8::TU) * ((a.nv + S8::TV - 1) / S8::TV);
}

Status launchExactSweep(const ExactSweepArgs& a, cudaStream_t stream) {
  if (auto s = prepareExactSweeps(); !s) return s;
  // Only density weights tell the two step rules apart: uniform weights cost len under both
  // (½(1 + 1)·len = len exactly), gradient and ascent weights belong to the edge a → b and both
  // rules charge w(a→b)·len (as the CPU backend's step_cost.h does).
  if (a.rule == StepRule::Trapezoid && a.weight == WeightRule::Density) {
    return launchTyped<StepRule::Trapezoid, WeightRule::Density>(a, stream);
  }
  switch (a.weight) {
    case WeightRule::Density: return launchTyped<StepRule::Entering, WeightRule::Density>(a, stream);
    case WeightRule::Uniform: return launchTyped<StepRule::Entering, WeightRule::Uniform>(a, stream);
    case WeightRule::Gradient: return launchTyped<StepRule::Entering, WeightRule::Gradient>(a, stream);
    case WeightRule::Ascent: return launchTyped<StepRule::Entering, WeightRule::Ascent>(a, stream);
  }
  return fail("WDT CUDA backend: unknown weight rule");
}

Status launchInitDistances(float* d, const std::uint8_t* seeds, std::size_t count, cudaStream_t stream) {
  if (count == 0) return {};
  const std::size_t blocks = (count + 255) / 256;
  initDistances<<<unsigned(blocks < 8192 ? blocks : 8192), 256, 0, stream>>>(d, seeds, count);
  return check(cudaGetLastError(), "launch of the distance initialisation kernel");
}

Status launchFill(float* d, std::size_t count, float value, cudaStream_t stream) {
  if (count == 0) return {};
  const std::size_t blocks = (count + 255) / 256;
  fill<<<unsigned(blocks < 8192 ? blocks : 8192), 256, 0, stream>>>(d, count, value);
  return check(cudaGetLastError(), "launch of the fill kernel");
}

}  // namespace at::cuda
