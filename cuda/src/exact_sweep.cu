// The sweep kernels: overlapped plane groups, equal to a serial sweep bit for bit.
//
// A sweep along axis a must visit its planes in order (plane p reads plane p∓1 after that plane's
// update), and one plane's update reaches one voxel further sideways per plane (a 45° cone). The
// sweep runs as ceil(planes / K) launches of K planes each (K = 8: 32 launches per sweep at 256³,
// not one per plane). In a launch, each block owns a TU × TV tile of lanes and computes its K
// planes in shared memory over the tile plus a halo that shrinks by one voxel per plane (K − 1 at
// the first plane, 0 at the last): exactly the cone the tile's results depend on. The halo voxels
// are recomputed redundantly from the same inputs, so they equal what the neighbouring block
// computes, and no block reads another block's output of the same launch.
//
// Inputs of a launch: the field before the sweep (`src`, never written during the sweep) for the
// planes' old values, and the final values of the plane before the group, written to `dst` by the
// previous launch (complete: launches on one stream are ordered). Outputs: the tile interiors of
// the K planes in `dst`. Every read is of data no thread writes during the launch, so the result
// is deterministic and identical to the CPU backend's serial sweep (same stencil, same order of
// float operations, no FMA contraction: --fmad=false).
//
// The x sweeps run on a copy of the field transposed to y-contiguous layout (as the CPU backend
// does), so that every sweep's lanes are coalesced along the contiguous axis.
#include <cuda_runtime.h>

#include <string>

#include "cuda_util.h"
#include "sweep_kernels.h"
#include "sweep_rules.cuh"

namespace at::cuda {
namespace {

constexpr int kTU = 32, kTV = 16;     // tile lanes: u contiguous
constexpr int kK = 8;                 // planes per launch
constexpr int kRU = kTU + 2 * kK;     // region including the widest read halo (K)
constexpr int kRV = kTV + 2 * kK;
constexpr int kRN = kRU * kRV;
constexpr int kThreads = 512;
static_assert(kRN % kThreads == 0, "the load loop covers the region exactly");
constexpr int kSlots = kK + 1;        // slot 0: the plane before the group; slots 1..K: its planes
constexpr std::size_t kSmemBytes = std::size_t(kSlots) * kRN * (sizeof(float) + 1);

struct GroupArgs {
  const float* src;
  float* dst;
  const std::uint8_t* q;
  int nu, nv, na;
  std::size_t strideV, strideA;
  int direction;
  int first;                 // step index (0-based, in sweep order) of the group's first plane
  wdt::SweepLengths lengths; // B = u, C = v
  float base;
  int* changed;
};

template <StepRule R, WeightRule W>
__global__ void __launch_bounds__(kThreads, 1) sweepGroup(GroupArgs p) {
  constexpr bool kQn = kNeedsNeighbourDensity<R, W>;
  extern __shared__ float smem[];
  float* sD = smem;                                                      // kSlots × kRN
  std::uint8_t* sQ = reinterpret_cast<std::uint8_t*>(smem + kSlots * kRN);  // kSlots × kRN

  const int u0 = int(blockIdx.x) * kTU - kK, v0 = int(blockIdx.y) * kTV - kK;  // region origin
  const int steps = min(kK, p.na - p.first);
  auto planeOffset = [&](int step) {
    const int a = p.direction > 0 ? step : p.na - 1 - step;
    return std::size_t(a) * p.strideA;
  };

  // Load: slot 0 = final values of the previous plane (dst), slots 1.. = old values (src). All of
  // a thread's loads go into registers first, then into shared memory, so they are all in flight
  // at once (the load phase is latency-bound otherwise).
  constexpr int kPer = kRN / kThreads;
  float dv[kSlots][kPer];
  std::uint8_t qv[kSlots][kPer];
#pragma unroll
  for (int slot = 0; slot < kSlots; ++slot) {
    const int step = p.first + slot - 1;
    const bool planeOk = slot <= steps && step >= 0;
    const std::size_t plane = planeOk ? planeOffset(step) : 0;
#pragma unroll
    for (int k = 0; k < kPer; ++k) {
      const int r = int(threadIdx.x) + k * kThreads;
      const int gu = u0 + r % kRU, gv = v0 + r / kRU;
      const bool ok = planeOk && gu >= 0 && gu < p.nu && gv >= 0 && gv < p.nv;
      const std::size_t i = ok ? std::size_t(gu) + std::size_t(gv) * p.strideV + plane : 0;
      dv[slot][k] = ok ? (slot == 0 ? p.dst[i] : __ldg(p.src + i)) : kInf;
      qv[slot][k] = ok && (slot > 0 || kQn) ? __ldg(p.q + i) : 0;
    }
  }
#pragma unroll
  for (int slot = 0; slot < kSlots; ++slot) {
#pragma unroll
    for (int k = 0; k < kPer; ++k) {
      sD[slot * kRN + int(threadIdx.x) + k * kThreads] = dv[slot][k];
      sQ[slot * kRN + int(threadIdx.x) + k * kThreads] = qv[slot][k];
    }
  }
  __syncthreads();

  // The plane loop is unrolled: each plane's halo h, region width and height are then constants
  // (no run-time division to find a thread's voxel) and so is its trip count.
  bool changed = false;
#pragma unroll
  for (int s = 1; s <= kK; ++s) {
    if (s <= steps) {  // uniform across the block
      const int h = kK - s;                       // valid halo at this plane
      const int w = kTU + 2 * h, hgt = kTV + 2 * h;
      const float* prev = sD + (s - 1) * kRN;
      const std::uint8_t* qPrev = sQ + (s - 1) * kRN;
      float* cur = sD + s * kRN;
      float* dstPlane = p.dst + planeOffset(p.first + s - 1);
#pragma unroll
      for (int i0 = 0; i0 < w * hgt; i0 += kThreads) {
        const int i = i0 + int(threadIdx.x);
        const int ru = kK - h + i % w, rv = kK - h + i / w;
        const int gu = u0 + ru, gv = v0 + rv;
        if (i < w * hgt && gu >= 0 && gu < p.nu && gv >= 0 && gv < p.nv) {  // else stays +infinity
          const int r = rv * kRU + ru;
          float n[3][3];
          std::uint8_t qn[3][3];
#pragma unroll
          for (int dc = 0; dc < 3; ++dc) {
#pragma unroll
            for (int db = 0; db < 3; ++db) {
              n[dc][db] = prev[r + (dc - 1) * kRU + (db - 1)];
              qn[dc][db] = kQn ? qPrev[r + (dc - 1) * kRU + (db - 1)] : 0;
            }
          }
          const float old = cur[r];
          const float v = relax<R, W>(old, n, qn, sQ[s * kRN + r], p.lengths, p.base);
          cur[r] = v;
          if (ru >= kK && ru < kK + kTU && rv >= kK && rv < kK + kTV) {
            changed |= v < old;
            dstPlane[std::size_t(gu) + std::size_t(gv) * p.strideV] = v;
          }
        }
      }
      __syncthreads();
    }
  }
  if (__syncthreads_or(changed) && threadIdx.x == 0) *p.changed = 1;
}

template <StepRule R, WeightRule W>
cudaError_t allowLargeSharedMemory() {
  return cudaFuncSetAttribute(sweepGroup<R, W>, cudaFuncAttributeMaxDynamicSharedMemorySize, int(kSmemBytes));
}

template <StepRule R, WeightRule W>
Status launchGroups(const ExactSweepArgs& a, cudaStream_t stream) {
  GroupArgs p{a.src, a.dst, a.density, a.nu, a.nv, a.na, a.strideV, a.strideA, a.direction, 0, a.lengths,
              a.baseCost, a.changed};
  const dim3 grid((a.nu + kTU - 1) / kTU, (a.nv + kTV - 1) / kTV);
  for (p.first = 0; p.first < a.na; p.first += kK) {
    sweepGroup<R, W><<<grid, kThreads, kSmemBytes, stream>>>(p);
  }
  return check(cudaGetLastError(), "launch of a sweep kernel");
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

Status prepareExactSweeps() {
  static const cudaError_t status = [] {
    cudaError_t e = allowLargeSharedMemory<StepRule::Trapezoid, WeightRule::Density>();
    if (e == cudaSuccess) e = allowLargeSharedMemory<StepRule::Entering, WeightRule::Density>();
    if (e == cudaSuccess) e = allowLargeSharedMemory<StepRule::Entering, WeightRule::Uniform>();
    if (e == cudaSuccess) e = allowLargeSharedMemory<StepRule::Entering, WeightRule::Gradient>();
    if (e == cudaSuccess) e = allowLargeSharedMemory<StepRule::Entering, WeightRule::Ascent>();
    return e;
  }();
  return check(status, "cudaFuncSetAttribute(sweep kernels, " + std::to_string(kSmemBytes) + " bytes of shared memory)");
}

Status launchExactSweep(const ExactSweepArgs& a, cudaStream_t stream) {
  if (a.rule == StepRule::Trapezoid && a.weight == WeightRule::Density) {
    return launchGroups<StepRule::Trapezoid, WeightRule::Density>(a, stream);
  }
  // Only density weights tell the two step rules apart: uniform weights cost len under both
  // (½(1 + 1)·len = len exactly), gradient and ascent weights belong to the edge a → b and both
  // rules charge w(a→b)·len (as the CPU backend's step_cost.h does).
  switch (a.weight) {
    case WeightRule::Density: return launchGroups<StepRule::Entering, WeightRule::Density>(a, stream);
    case WeightRule::Uniform: return launchGroups<StepRule::Entering, WeightRule::Uniform>(a, stream);
    case WeightRule::Gradient: return launchGroups<StepRule::Entering, WeightRule::Gradient>(a, stream);
    case WeightRule::Ascent: return launchGroups<StepRule::Entering, WeightRule::Ascent>(a, stream);
  }
  return fail("WDT CUDA backend: unknown weight rule");
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
