// The persistent sweep kernel: one launch a sweep whose tiles walk their plane groups themselves
// (see sweepPersistent). Used by launchExactSweep (exact_sweep.cu) where setPersistentSweeps asks
// for it and the blocks all fit the GPU at once.
#include <cuda_runtime.h>

#include <cstdint>

#include "cuda_util.h"
#include "sweep_kernels.h"
#include "sweep_rules.cuh"
#include "sweep_tiles.cuh"

namespace at::cuda {
namespace {

// ─── Persistent sweep (by default for the large tile only: setPersistentSweeps) ───
// One launch per sweep: each block owns one tile for the whole sweep and walks its plane groups
// itself, so the per-slot set-up (region walk, offsets) is paid once a sweep, not once a group,
// and no launch links the groups. Before group g (g > 0) a block waits until its own tile and its
// 8 neighbours have published progress ≥ g, i.e. written the plane before the group (the only
// plane of dst that a group reads: its halo is at most K ≤ TU, TV voxels wide, so only the 8
// neighbours' tiles). A block publishes g + 1 after its group's last plane: its threads' stores,
// a block barrier, then one thread's fence and release store (the grid-barrier pattern). Every
// plane of dst is written once a sweep and src is never written, so there is no write-after-read
// hazard and the result is the group launches' (and the CPU's) bit for bit. Blocks must all be
// resident at once (spinning blocks would otherwise starve the unscheduled ones): the launch is
// cooperative, which the runtime refuses when they do not fit.
__device__ __forceinline__ unsigned loadAcquire(const unsigned* p) {
  unsigned v;
  asm volatile("ld.acquire.gpu.global.u32 %0, [%1];" : "=r"(v) : "l"(p) : "memory");
  return v;
}
__device__ __forceinline__ void storeRelease(unsigned* p, unsigned v) {
  asm volatile("st.release.gpu.global.u32 [%0], %1;" ::"l"(p), "r"(v) : "memory");
}

// Measured on an H200 (bench/RESULTS.md): faster than the group launches for the large tile (512³
// 5.17 against 5.30 ms a pass), slower for the one-wave tile (256³ 1.24 against 1.03: one block a
// multiprocessor cannot overlap a group's set-up with the group before, as the group launches'
// second resident block does). Slower still there: loading a group's old values during the group
// before (1.26) and 32 × 8 tiles, two blocks a multiprocessor (1.33 with 6 planes, 1.53 with 4).
template <class S, CostKernel Cost>
__global__ void __launch_bounds__(S::T, S::MinBlocks) sweepPersistent(GroupArgs p, unsigned* progress) {
  static_assert(S::K <= S::TU && S::K <= S::TV, "a group's halo reaches only the 8 neighbouring tiles");
  constexpr bool kQn = wdt::needsNeighbourDensity(Cost);
  constexpr int K = S::K, Slots = S::Slots, Pitch = S::Pitch;
  __shared__ float sD[2][S::PlaneFloats];
  __shared__ std::uint8_t sQ[kQn ? 2 : 1][kQn ? S::PlaneFloats : 1];
  extern __shared__ std::uint8_t sQown[];
  auto qOwn = [&](int plane, int k) -> std::uint8_t& { return sQown[(plane * Slots + k) * S::T + int(threadIdx.x)]; };

  const int u0 = int(blockIdx.x) * S::TU - K, v0 = int(blockIdx.y) * S::TV - K;
  auto planeOffset = [&](int step) {
    const int a = p.direction > 0 ? step : p.na - 1 - step;
    return std::size_t(a) * p.strideA;
  };
  // Per slot, once a sweep: shared index, offset within a plane, the last plane of a full group
  // that computes it (0: none).
  int r[Slots], lastFull[Slots];
  bool inRegion[Slots], inside[Slots];
  unsigned g[Slots];
#pragma unroll
  for (int k = 0; k < Slots; ++k) {
    const RegionVoxel v = regionVoxel<S>(int(threadIdx.x) + k * S::T);
    const int gu = u0 + v.ru, gv = v0 + v.rv;
    r[k] = v.rv * Pitch + v.ru;
    inRegion[k] = v.ring <= K;
    inside[k] = inRegion[k] && gu >= 0 && gu < p.nu && gv >= 0 && gv < p.nv;
    g[k] = inside[k] ? unsigned(gu) + unsigned(gv) * unsigned(p.strideV) : 0u;
    lastFull[k] = !inside[k] ? 0 : k < S::CoreSlots ? K : K - v.ring;
  }
  // This thread's neighbour tile to wait for (threads 0–8; -1: none or outside the grid).
  int waitTile = -1;
  if (threadIdx.x < 9) {
    const int tu = int(blockIdx.x) + int(threadIdx.x) % 3 - 1, tv = int(blockIdx.y) + int(threadIdx.x) / 3 - 1;
    if (tu >= 0 && tu < int(gridDim.x) && tv >= 0 && tv < int(gridDim.y)) waitTile = tv * int(gridDim.x) + tu;
  }
  const int myTile = int(blockIdx.y) * int(gridDim.x) + int(blockIdx.x);

  // Old values and densities of the group starting at plane `first` (never written during the
  // sweep; nothing past the last plane).
  auto loadGroup = [&](int first, float (&oldD)[K][Slots], std::uint8_t (&q)[K][Slots]) {
    const int steps = min(K, p.na - first);
#pragma unroll
    for (int s = 1; s <= K; ++s) {
      const std::size_t plane = s <= steps ? planeOffset(first + s - 1) : 0;
#pragma unroll
      for (int k = 0; k < Slots; ++k) {
        const bool used = s <= steps && s <= S::lastPlaneOfSlot(k) && s <= lastFull[k];
        oldD[s - 1][k] = used ? __ldcg(p.src + plane + g[k]) : kInf;
        q[s - 1][k] = used ? __ldg(p.q + plane + g[k]) : 0;
      }
    }
  };

  int lowered = 0;
  unsigned group = 0;
  for (int first = 0; first < p.na; first += K, ++group) {
    const int steps = min(K, p.na - first);
    int last[Slots];
#pragma unroll
    for (int k = 0; k < Slots; ++k) last[k] = min(steps, lastFull[k]);
    auto active = [&](int k, int s) { return s <= S::lastPlaneOfSlot(k) && s <= last[k]; };
    // The group's loads, in flight while this block waits for its neighbours; all issued before
    // the first store into shared memory (a store waits for its load).
    float oldD[K][Slots];
    std::uint8_t q[K][Slots];
    loadGroup(first, oldD, q);
#pragma unroll
    for (int s = 1; s <= K; ++s) {
#pragma unroll
      for (int k = 0; k < Slots; ++k) {
        if (s <= S::lastPlaneOfSlot(k)) qOwn(s - 1, k) = q[s - 1][k];
      }
    }
    const bool hasPrev = first > 0;
    const std::size_t prevPlane = hasPrev ? planeOffset(first - 1) : 0;
#pragma unroll
    for (int k = 0; k < Slots; ++k) {
      if (inRegion[k]) {
        sD[1][r[k]] = kInf;
        if constexpr (kQn) {
          sQ[0][r[k]] = hasPrev && inside[k] ? __ldg(p.q + prevPlane + g[k]) : 0;
          sQ[1][r[k]] = 0;
        }
      }
    }
    if (hasPrev && waitTile >= 0) {
      while (loadAcquire(progress + waitTile) < group) {
      }
    }
    __syncthreads();  // the neighbours' planes before the group are visible to every thread
    float prevD[Slots];
#pragma unroll
    for (int k = 0; k < Slots; ++k) prevD[k] = hasPrev && inside[k] ? __ldcg(p.dst + prevPlane + g[k]) : kInf;
#pragma unroll
    for (int k = 0; k < Slots; ++k) {
      if (inRegion[k]) sD[0][r[k]] = prevD[k];
    }
    __syncthreads();
#pragma unroll
    for (int s = 1; s <= K; ++s) {
      if (s <= steps) {
        const float* prev = sD[(s - 1) & 1];
        float* cur = sD[s & 1];
        const std::uint8_t* qPrev = sQ[kQn ? (s - 1) & 1 : 0];
        float* dstPlane = p.dst + planeOffset(first + s - 1);
#pragma unroll
        for (int k = 0; k < Slots; ++k) {
          if (active(k, s)) {
            float n[3][3];
            std::uint8_t qn[3][3];
            gatherNeighbours<kQn>(prev, qPrev, r[k], 1, Pitch, n, qn);
            const float old = oldD[s - 1][k];
            const std::uint8_t qv = qOwn(s - 1, k);
            const float v = wdt::relaxVoxel<Cost>(old, n, qn, qv, p.lengths, p.base);
            cur[r[k]] = v;
            if constexpr (kQn) sQ[s & 1][r[k]] = qv;
            if (k < S::CoreSlots) {
              lowered += v < old;
              dstPlane[g[k]] = v;
            }
          }
        }
        __syncthreads();
      }
    }
    if (threadIdx.x == 0) {
      __threadfence();
      storeRelease(progress + myTile, group + 1);
    }
  }
  __shared__ int warpLowered[S::T / 32];
  lowered = __reduce_add_sync(0xffffffffu, lowered);
  if ((threadIdx.x & 31) == 0) warpLowered[threadIdx.x / 32] = lowered;
  __syncthreads();
  if (threadIdx.x == 0) {
    int sum = 0;
#pragma unroll
    for (int i = 0; i < S::T / 32; ++i) sum += warpLowered[i];
    if (sum) atomicAdd(p.lowered, static_cast<unsigned long long>(sum));
  }
}

// Launches the persistent sweep if its blocks all fit the GPU at once; *launched says whether it
// did (false: the caller launches the groups instead).
template <class S, CostKernel Cost>
Status launchPersistent(const ExactSweepArgs& a, cudaStream_t stream, bool* launched) {
  *launched = false;
  constexpr std::size_t dynamicBytes = std::size_t(S::K) * S::Slots * S::T;
  auto kernel = sweepPersistent<S, Cost>;
  static const cudaError_t raised = cudaFuncSetAttribute(reinterpret_cast<const void*>(kernel),
                                                         cudaFuncAttributeMaxDynamicSharedMemorySize, int(dynamicBytes));
  if (raised != cudaSuccess) return check(raised, "cudaFuncSetAttribute (persistent sweep shared memory)");
  int device = 0, multiprocessors = 0, perMultiprocessor = 0, cooperative = 0;
  if (const cudaError_t e = cudaGetDevice(&device); e != cudaSuccess) return check(e, "cudaGetDevice");
  if (const cudaError_t e = cudaDeviceGetAttribute(&multiprocessors, cudaDevAttrMultiProcessorCount, device);
      e != cudaSuccess)
    return check(e, "cudaDeviceGetAttribute (multiprocessor count)");
  if (const cudaError_t e = cudaDeviceGetAttribute(&cooperative, cudaDevAttrCooperativeLaunch, device); e != cudaSuccess)
    return check(e, "cudaDeviceGetAttribute (cooperative launch)");
  if (!cooperative) return {};  // no co-residency guarantee: group launches
  if (const cudaError_t e = cudaOccupancyMaxActiveBlocksPerMultiprocessor(&perMultiprocessor, kernel, S::T, dynamicBytes);
      e != cudaSuccess)
    return check(e, "cudaOccupancyMaxActiveBlocksPerMultiprocessor (persistent sweep)");
  const dim3 grid((a.nu + S::TU - 1) / S::TU, (a.nv + S::TV - 1) / S::TV);
  if ((long long)grid.x * grid.y > (long long)multiprocessors * perMultiprocessor ||
      (long long)grid.x * grid.y > (long long)kSweepProgressCounters)
    return {};
  if (a.zeroProgress) AT_TRY(a.zeroProgress());
  GroupArgs p{a.src, a.dst, a.density, a.nu, a.nv, a.na, a.strideV, a.strideA, a.direction, 0, a.lengths,
              a.baseCost, a.lowered};
  cudaLaunchConfig_t config{};
  config.gridDim = grid;
  config.blockDim = dim3(S::T);
  config.dynamicSmemBytes = dynamicBytes;
  config.stream = stream;
  cudaLaunchAttribute attribute{};
  attribute.id = cudaLaunchAttributeCooperative;
  attribute.val.cooperative = 1;
  config.attrs = &attribute;
  config.numAttrs = 1;
  if (const cudaError_t e = cudaLaunchKernelEx(&config, kernel, p, a.progress); e != cudaSuccess)
    return check(e, "launch of the persistent sweep kernel");
  *launched = true;
  return {};
}

}  // namespace

Status launchPersistentSweep(const ExactSweepArgs& a, bool oneWaveTile, cudaStream_t stream, bool* launched) {
  *launched = false;
  return launchForRule(a.rule, a.weight, [&]<CostKernel Cost>() -> Status {
    return oneWaveTile ? launchPersistent<OneWaveShape, Cost>(a, stream, launched)
                       : launchPersistent<LargeShape, Cost>(a, stream, launched);
  });
}

}  // namespace at::cuda
