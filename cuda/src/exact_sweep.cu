// The sweep kernels: overlapped plane groups, equal to a serial sweep bit for bit.
//
// A sweep along axis a must visit its planes in order (plane p reads plane p∓1 after that plane's
// update), and one plane's update reaches one voxel further sideways per plane (a 45° cone). The
// sweep runs as ceil(planes / K) launches of K planes each (K = 6 or 8, TileShape: 43 or 32
// launches per sweep at 256³, not one per plane). In a launch, each block owns a TU × TV tile of
// lanes and computes its K
// planes in shared memory over the tile plus a halo that shrinks by one voxel per plane (K − 1 at
// the first plane, 0 at the last): exactly the cone the tile's results depend on. The halo voxels
// are recomputed redundantly from the same inputs, so they equal what the neighbouring block
// computes, and no block reads another block's output of the same launch.
//
// Inputs of a launch: the field before the sweep (`src`, never written during the sweep) for the
// planes' old values, and the final values of the plane before the group, written to `dst` by the
// previous launch. Outputs: the tile interiors of the K planes in `dst`. Every read is of data no
// thread writes during the launch, so the result is deterministic and identical to the CPU
// backend's serial sweep (same stencil, same float operations, no FMA contraction: --fmad=false).
//
// Launches overlap through programmatic dependent launch (sm_90): a group's blocks start while the
// previous group still runs, load their old values and densities, and only then wait for the
// previous grid to complete before reading the plane it wrote (details at sweepGroup).
//
// The x sweeps run on a copy of the field transposed to y-contiguous layout (as the CPU backend
// does), so that every sweep's lanes are coalesced along the contiguous axis.
#include <cuda_runtime.h>

#include <cstdlib>
#include <string>

#include "cuda_util.h"
#include "sweep_kernels.h"
#include "sweep_rules.cuh"
#include "sweep_tiles.cuh"

namespace at::cuda {
namespace {
// Programmatic dependent launch: waitForPreviousGrid blocks until the grids this one depends on
// have completed and their writes are visible (a no-op without the launch attribute);
// allowNextGrid lets the next grid be scheduled once every block of this one has called it.
__device__ __forceinline__ void waitForPreviousGrid() { asm volatile("griddepcontrol.wait;" ::: "memory"); }
__device__ __forceinline__ void allowNextGrid() { asm volatile("griddepcontrol.launch_dependents;" ::: "memory"); }

// One group of K planes of a sweep. Each thread owns Slots fixed voxels of the region for the
// whole launch, numbered as in regionVoxel: the voxels computed at plane s (rings ≤ K − s) are a
// prefix of the numbering, so whole warps drop out as the halo shrinks. A voxel's old values and
// densities for all K planes are loaded into registers up front (all loads in flight at once, each
// waited for only when its plane comes), so shared memory holds just two planes of distances, the
// previous and the current, and no index is computed per plane.
//
// A group after the first of its sweep loads its old values while the previous group still runs:
// those planes were written by the previous sweep, whose grids completed before the previous group
// passed its wait. Distances are read through L2 only (ld.global.cg): an L1 line filled by an
// older grid still running on the same multiprocessor can be stale (reading them through L1 gave
// wrong fields on an H100). The first group of a sweep reads planes the previous sweep's last group
// may still be writing, so it waits first.
//
// kOneWave (named for the launches whose blocks fit the multiprocessors at once, e.g. 256³ and
// smaller on an H200, where every block starts while the previous group runs, so its old values
// and densities have arrived by the time the wait returns): a block keeps its density bytes in its
// own shared-memory column, which leaves the registers to issue the previous plane's loads of all
// slots before the first is stored: one L2 round trip after the wait instead of one a slot. A
// block of a later wave starts once the previous group is done and waits for those densities
// first, an extra round trip: with the default tile that lost 1.7 % at 512³ (measured on an H200,
// bench/RESULTS.md: −6 % a pass at 128³, −1 % at 256³), but the large tile, whose registers
// could not hold them, takes this kernel in every wave.
template <class S, CostKernel Cost, bool kWide, bool kOneWave>
__global__ void __launch_bounds__(S::T, S::MinBlocks) sweepGroup(GroupArgs p) {
  constexpr bool kQn = wdt::needsNeighbourDensity(Cost);
  constexpr int K = S::K, Slots = S::Slots, Pitch = S::Pitch;
  __shared__ float sD[2][S::PlaneFloats];
  __shared__ std::uint8_t sQ[kQn ? 2 : 1][kQn ? S::PlaneFloats : 1];

  const int u0 = int(blockIdx.x) * S::TU - K, v0 = int(blockIdx.y) * S::TV - K;  // region origin
  const int steps = min(K, p.na - p.first);
  // Offsets: a voxel's is base(plane) + g (g 32 bits). Narrow (kWide false, every plane set of
  // fewer than 2³² voxels): base is the plane's offset and g the voxel's within the plane. Wide
  // (larger volumes, e.g. 2048³): base also holds the region origin's offset (signed: the origin
  // lies one halo before the grid at its low edges) and g is the voxel's offset from the origin,
  // ru + rv · strideV. The narrow form is 1–2 % faster (measured on an H200, bench/RESULTS.md).
  const std::ptrdiff_t origin =
      kWide ? std::ptrdiff_t(u0) + std::ptrdiff_t(v0) * std::ptrdiff_t(p.strideV) : std::ptrdiff_t(0);
  auto planeOffset = [&](int step) {
    const int a = p.direction > 0 ? step : p.na - 1 - step;
    if constexpr (kWide) return std::ptrdiff_t(a) * std::ptrdiff_t(p.strideA) + origin;
    else return std::size_t(a) * p.strideA;
  };

  // Per slot: shared-memory index, voxel offset g (above), and the last plane of the group that
  // computes it (0: none; tile voxels every plane, halo ring ρ up to plane K − ρ).
  int r[Slots], last[Slots];
  bool inRegion[Slots], inside[Slots];
  unsigned g[Slots];
#pragma unroll
  for (int k = 0; k < Slots; ++k) {
    const RegionVoxel v = regionVoxel<S>(int(threadIdx.x) + k * S::T);
    const int gu = u0 + v.ru, gv = v0 + v.rv;
    r[k] = v.rv * Pitch + v.ru;
    inRegion[k] = v.ring <= K;
    inside[k] = inRegion[k] && gu >= 0 && gu < p.nu && gv >= 0 && gv < p.nv;
    g[k] = !inside[k] ? 0u
           : kWide    ? unsigned(v.ru) + unsigned(v.rv) * unsigned(p.strideV)
                      : unsigned(gu) + unsigned(gv) * unsigned(p.strideV);
    last[k] = !inside[k] ? 0 : k < S::CoreSlots ? steps : min(steps, K - v.ring);
  }
  auto active = [&](int k, int s) { return s <= S::lastPlaneOfSlot(k) && s <= last[k]; };

  if (p.first == 0) {
    waitForPreviousGrid();
    allowNextGrid();
  }
  float oldD[K][Slots];
  std::uint8_t q[K][Slots];
  // One-wave launches: [plane][slot][thread] density bytes, in dynamic shared memory
  // (sharedBytesOf: the large tile's would not fit the 48 KB of static shared memory).
  extern __shared__ std::uint8_t sQown[];
  auto qOwn = [&](int plane, int k) -> std::uint8_t& { return sQown[(plane * Slots + k) * S::T + int(threadIdx.x)]; };
#pragma unroll
  for (int s = 1; s <= K; ++s) {
    const auto plane = s <= steps ? planeOffset(p.first + s - 1) : 0;
#pragma unroll
    for (int k = 0; k < Slots; ++k) {
      const bool used = active(k, s);
      oldD[s - 1][k] = used ? __ldcg(p.src + plane + g[k]) : kInf;
      q[s - 1][k] = used ? __ldg(p.q + plane + g[k]) : 0;
    }
  }
  const bool hasPrev = p.first > 0;
  const auto prevPlane = hasPrev ? planeOffset(p.first - 1) : 0;
  if constexpr (kOneWave) {
    // Densities (read back by the same thread only: no barrier) and the previous plane's, which
    // never change during a sweep, before the wait; voxels outside the grid stay +infinity.
#pragma unroll
    for (int s = 1; s <= K; ++s) {
#pragma unroll
      for (int k = 0; k < Slots; ++k) {
        if (s <= S::lastPlaneOfSlot(k)) qOwn(s - 1, k) = q[s - 1][k];
      }
    }
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
    if (p.first > 0) {
      waitForPreviousGrid();  // the plane before the group, read next, is complete
      allowNextGrid();
    }
    float prevD[Slots];  // all loads issued before the first store
#pragma unroll
    for (int k = 0; k < Slots; ++k) prevD[k] = hasPrev && inside[k] ? __ldcg(p.dst + prevPlane + g[k]) : kInf;
#pragma unroll
    for (int k = 0; k < Slots; ++k) {
      if (inRegion[k]) sD[0][r[k]] = prevD[k];
    }
  } else {
    if (p.first > 0) {
      waitForPreviousGrid();  // the plane before the group, read next, is complete
      allowNextGrid();
    }
#pragma unroll
    for (int k = 0; k < Slots; ++k) {
      if (inRegion[k]) {
        const bool load = hasPrev && inside[k];
        sD[0][r[k]] = load ? __ldcg(p.dst + prevPlane + g[k]) : kInf;
        sD[1][r[k]] = kInf;  // voxels outside the grid stay +infinity in both planes
        if constexpr (kQn) {
          sQ[0][r[k]] = load ? __ldg(p.q + prevPlane + g[k]) : 0;
          sQ[1][r[k]] = 0;
        }
      }
    }
  }
  __syncthreads();

  int lowered = 0;  // tile voxels of this thread that the group lowered
#pragma unroll
  for (int s = 1; s <= K; ++s) {
    if (s <= steps) {  // uniform across the block
      const float* prev = sD[(s - 1) & 1];
      float* cur = sD[s & 1];
      const std::uint8_t* qPrev = sQ[kQn ? (s - 1) & 1 : 0];
      float* dstPlane = p.dst + planeOffset(p.first + s - 1);
#pragma unroll
      for (int k = 0; k < Slots; ++k) {
        if (active(k, s)) {
          float n[3][3];
          std::uint8_t qn[3][3];
          gatherNeighbours<kQn>(prev, qPrev, r[k], 1, Pitch, n, qn);
          const float old = oldD[s - 1][k];
          const std::uint8_t qv = kOneWave ? qOwn(s - 1, k) : q[s - 1][k];
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
  // The block's count: each warp's sum into shared memory, one barrier, then one global add by
  // thread 0.
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

// Dynamic shared memory of a sweepGroup launch: the one-wave kernels' density column.
template <class S, bool kOneWave>
constexpr std::size_t sharedBytesOf() {
  return kOneWave ? std::size_t(S::K) * S::Slots * S::T : 0;
}

template <class S, CostKernel Cost, bool kWide, bool kOneWave>
Status launchGroups(const ExactSweepArgs& a, cudaStream_t stream) {
  constexpr std::size_t dynamicBytes = sharedBytesOf<S, kOneWave>();
  if constexpr (dynamicBytes > 0) {
    static const cudaError_t raised = cudaFuncSetAttribute(
        reinterpret_cast<const void*>(sweepGroup<S, Cost, kWide, kOneWave>),
        cudaFuncAttributeMaxDynamicSharedMemorySize, int(dynamicBytes));
    if (raised != cudaSuccess) return check(raised, "cudaFuncSetAttribute (sweep kernel shared memory)");
  }
  GroupArgs p{a.src, a.dst, a.density, a.nu, a.nv, a.na, a.strideV, a.strideA, a.direction, 0, a.lengths,
              a.baseCost, a.lowered};
  cudaLaunchConfig_t config{};
  config.gridDim = dim3((a.nu + S::TU - 1) / S::TU, (a.nv + S::TV - 1) / S::TV);
  config.blockDim = dim3(S::T);
  config.dynamicSmemBytes = dynamicBytes;
  config.stream = stream;
  cudaLaunchAttribute attribute{};
  attribute.id = cudaLaunchAttributeProgrammaticStreamSerialization;
  attribute.val.programmaticStreamSerializationAllowed = 1;
  config.attrs = &attribute;
  config.numAttrs = 1;
  for (p.first = 0; p.first < a.na; p.first += S::K) {
    if (const cudaError_t e = cudaLaunchKernelEx(&config, sweepGroup<S, Cost, kWide, kOneWave>, p); e != cudaSuccess)
      return check(e, "launch of a sweep kernel");
  }
  return {};
}

template <class T>
__global__ void transposeXY(const T* __restrict__ in, T* __restrict__ out, int nx, int ny) {
  __shared__ T tile[32][33];
  const std::size_t slice = std::size_t(nx) * ny * blockIdx.z;
  const int x0 = blockIdx.x * 32, y0 = blockIdx.y * 32;
  for (int dy = threadIdx.y; dy < 32; dy += 8) {
    const int x = x0 + threadIdx.x, y = y0 + dy;
    if (x < nx && y < ny) tile[dy][threadIdx.x] = in[slice + x + std::size_t(nx) * y];
  }
  __syncthreads();
  for (int dx = threadIdx.y; dx < 32; dx += 8) {
    const int y = y0 + threadIdx.x, x = x0 + dx;
    if (x < nx && y < ny) out[slice + y + std::size_t(ny) * x] = tile[threadIdx.x][dx];
  }
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

Status launchExactSweep(const ExactSweepArgs& a, cudaStream_t stream) {
  if (std::size_t(Shape::RV) * a.strideV + std::size_t(Shape::RU) > std::size_t(0xffffffffu)) {
    return fail("WDT CUDA backend: plane rows of stride " + std::to_string(a.strideV) +
                " exceed the kernels' 32-bit voxel offsets within a tile");
  }
  // Narrow offsets while every voxel of a plane set fits 32 bits from the plane's start.
  const bool wide = std::size_t(a.nv - 1) * a.strideV + std::size_t(a.nu) > std::size_t(0xffffffffu);
  int device = 0, multiprocessors = 0;
  if (const cudaError_t e = cudaGetDevice(&device); e != cudaSuccess) return check(e, "cudaGetDevice");
  if (const cudaError_t e = cudaDeviceGetAttribute(&multiprocessors, cudaDevAttrMultiProcessorCount, device);
      e != cudaSuccess)
    return check(e, "cudaDeviceGetAttribute (multiprocessor count)");
  auto blocksOf = [&]<class S>() {
    return (long long)((a.nu + S::TU - 1) / S::TU) * (long long)((a.nv + S::TV - 1) / S::TV);
  };
  const bool oneWave = blocksOf.template operator()<Shape>() <= multiprocessors;
  // The large tile wherever the default tile needs more than one wave (AT_WDT_CUDA_LARGE_TILE=0
  // keeps the default tile there, for comparisons on one machine).
  static const bool largeTileAllowed = [] {
    const char* v = std::getenv("AT_WDT_CUDA_LARGE_TILE");
    return !(v && std::string(v) == "0");
  }();
  return launchForRule(a.rule, a.weight, [&]<CostKernel Cost>() -> Status {
    if (wide) return launchGroups<Shape, Cost, true, false>(a, stream);
    // One persistent launch a sweep (a.persistent) where its blocks fit the GPU at once.
    if (a.progress && a.persistent != PersistentTiles::None) {
      bool launched = false;
      if (oneWave && a.persistent == PersistentTiles::All) {
        AT_TRY(launchPersistentSweep(a, true, stream, &launched));
      } else if (!oneWave && largeTileAllowed) {
        AT_TRY(launchPersistentSweep(a, false, stream, &launched));
      }
      if (launched) {
        if (a.persistentLaunches) ++*a.persistentLaunches;
        return {};
      }
    }
    if (oneWave) return launchGroups<OneWaveShape, Cost, false, true>(a, stream);
    if (largeTileAllowed) return launchGroups<LargeShape, Cost, false, true>(a, stream);
    return launchGroups<Shape, Cost, false, false>(a, stream);
  });
}

template <class T>
Status launchTransposeXY(const T* in, T* out, int nx, int ny, int nz, cudaStream_t stream) {
  const dim3 grid((nx + 31) / 32, (ny + 31) / 32, nz);
  transposeXY<T><<<grid, dim3(32, 8), 0, stream>>>(in, out, nx, ny);
  return check(cudaGetLastError(), "launch of the transpose kernel");
}
template Status launchTransposeXY<float>(const float*, float*, int, int, int, cudaStream_t);
template Status launchTransposeXY<std::uint8_t>(const std::uint8_t*, std::uint8_t*, int, int, int, cudaStream_t);

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
