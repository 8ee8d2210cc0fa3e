// The WDT sweep kernels: one launch per sweep, every voxel's arithmetic from wdt/stencil.h.
//
// Design (deterministic tiled sweeps)
// -----------------------------------
// A sweep along axis a visits the planes perpendicular to a in order; voxel b of plane p takes the
// minimum over its 9 neighbours in plane p∓1 (the previous plane in sweep order). A sweep runs as
// ONE kernel launch: each thread block owns a tile of the sweep plane and marches through all
// planes in order, so a pass is six launches, not one per plane.
//
// Every value a thread reads is either
//   * block-local: a neighbour inside the block's tile comes from this sweep's updated previous
//     plane, held in shared memory and ordered by a barrier between planes, or
//   * immutable: the sweep reads `src` (the field as it was when the sweep started) and writes a
//     separate `dst` (ping-pong buffers), so a neighbour outside the tile (the halo ring) is the
//     snapshot value from `src`, which no block writes during the sweep.
// No thread ever reads a value another block may or may not have written yet, so results are
// bitwise reproducible. The price: information crosses a tile border with the snapshot value,
// i.e. one sweep later than in a serial raster scan. Every value is still the cost of some real
// path (never below the exact distance) and the fixed point — where no relaxation changes
// anything — is the same as the CPU's, so converged fields agree; fixed-pass fields are higher
// than the CPU's. Measured (bench/RESULTS.md, H100, 256³ synthetic head): 0.63 ms per pass but a
// mean relative error of 4.8 % after 2 passes (CPU: 1.6e-5) and 18 passes to converge (CPU: 5).
// That lag is why this scheme is not the default (exact_sweep.cu is); AT_WDT_CUDA_SCHEME=tiled
// selects it.
//
// y and z sweeps (the plane contains the contiguous x axis): tiles of 32 x-lanes × 8 lanes along
// the other plane axis, one thread per lane; loads and stores are coalesced along x. Everything a
// thread loads is immutable during the sweep, so loads are issued kGroup planes ahead (register
// double buffering) and only the shared-memory chain is serial.
//
// x sweeps (the plane is yz, marching along contiguous x): one warp per tile of 8×4 (y,z) lines.
// The warp loads chunks of 32 consecutive x values of its 10×6 lines (tile + halo) into shared
// memory with coalesced reads, marches the 32 steps in order (__syncwarp between steps), and
// writes the chunk back coalesced.
#include "sweep_kernels.h"

#include <cuda_runtime.h>

#include <cmath>
#include <string>

#include "cuda_util.h"
#include "sweep_rules.cuh"

namespace at::cuda {
namespace {

// ---- y / z sweeps ----------------------------------------------------------------------------

constexpr int kTileX = 32;                            // lanes along x (contiguous)
constexpr int kTileB = 8;                             // lanes along the other plane axis
constexpr int kRing = 2 * (kTileX + 2) + 2 * kTileB;  // halo voxels around the tile
constexpr int kGroup = 8;                             // planes loaded ahead
static_assert(kRing <= kTileX * kTileB, "one thread per halo voxel");

struct PlaneSweep {
  const float* src;
  float* dst;
  const std::uint8_t* q;
  int nx, nb, na;          // lanes along x, along the other plane axis, planes
  std::size_t strideB, strideA;
  int direction;
  wdt::SweepLengths lengths;  // B = x lanes, C = the other plane axis (axisSweepLengths' order)
  float base;
  int* changed;
};

template <StepRule R, WeightRule W>
__global__ void __launch_bounds__(kTileX* kTileB) sweepAlongPlanes(PlaneSweep p) {
  constexpr bool kQn = kNeedsNeighbourDensity<R, W>;
  __shared__ float sD[2][kTileB + 2][kTileX + 2];
  __shared__ std::uint8_t sQ[2][kTileB + 2][kTileX + 2];

  const int tx = threadIdx.x, tb = threadIdx.y, t = tb * kTileX + tx;
  const int x = blockIdx.x * kTileX + tx, b = blockIdx.y * kTileB + tb;
  const bool inside = x < p.nx && b < p.nb;
  const std::size_t lane = inside ? std::size_t(x) + std::size_t(b) * p.strideB : 0;

  // Halo ring: thread t < kRing owns one ring position (rx, rb) in tile coordinates.
  const bool hasRing = t < kRing;
  int rx = 0, rb = 0;
  if (t < kTileX + 2) {
    rx = t - 1, rb = -1;
  } else if (t < 2 * (kTileX + 2)) {
    rx = t - (kTileX + 2) - 1, rb = kTileB;
  } else if (t < 2 * (kTileX + 2) + kTileB) {
    rx = -1, rb = t - 2 * (kTileX + 2);
  } else {
    rx = kTileX, rb = t - 2 * (kTileX + 2) - kTileB;
  }
  const int gx = blockIdx.x * kTileX + rx, gb = blockIdx.y * kTileB + rb;
  const bool ringInside = hasRing && gx >= 0 && gx < p.nx && gb >= 0 && gb < p.nb;
  const std::size_t ringLane = ringInside ? std::size_t(gx) + std::size_t(gb) * p.strideB : 0;

  // Buffer 1 is "plane −1": out of the grid, +infinity.
  sD[1][tb + 1][tx + 1] = kInf;
  sQ[1][tb + 1][tx + 1] = 0;
  if (hasRing) {
    sD[1][rb + 1][rx + 1] = kInf;
    sQ[1][rb + 1][rx + 1] = 0;
  }

  auto planeOffset = [&](int s) {
    const int a = p.direction > 0 ? s : p.na - 1 - s;
    return std::size_t(a) * p.strideA;
  };
  float cur[kGroup], ring[kGroup];
  std::uint8_t qCur[kGroup], qRing[kGroup];
  auto load = [&](int s0, float* c, std::uint8_t* qc, float* r, std::uint8_t* qr) {
#pragma unroll
    for (int g = 0; g < kGroup; ++g) {
      const int s = s0 + g;
      const bool planeOk = s < p.na;
      const std::size_t off = planeOk ? planeOffset(s) : 0;
      c[g] = inside && planeOk ? __ldg(p.src + lane + off) : kInf;
      qc[g] = inside && planeOk ? __ldg(p.q + lane + off) : 0;
      r[g] = ringInside && planeOk ? __ldg(p.src + ringLane + off) : kInf;
      if constexpr (kQn) qr[g] = ringInside && planeOk ? __ldg(p.q + ringLane + off) : 0;
      else qr[g] = 0;
    }
  };
  load(0, cur, qCur, ring, qRing);
  __syncthreads();

  bool changed = false;
  for (int s0 = 0; s0 < p.na; s0 += kGroup) {
    float nCur[kGroup], nRing[kGroup];
    std::uint8_t nqCur[kGroup], nqRing[kGroup];
    load(s0 + kGroup, nCur, nqCur, nRing, nqRing);
#pragma unroll
    for (int g = 0; g < kGroup; ++g) {
      const int s = s0 + g;
      if (s >= p.na) break;  // uniform across the block
      const int prev = (s + 1) & 1, out = s & 1;
      float v = cur[g];
      if (inside) {
        float n[3][3];
        std::uint8_t qn[3][3];
#pragma unroll
        for (int dc = 0; dc < 3; ++dc) {
#pragma unroll
          for (int db = 0; db < 3; ++db) {
            n[dc][db] = sD[prev][tb + dc][tx + db];
            qn[dc][db] = kQn ? sQ[prev][tb + dc][tx + db] : 0;
          }
        }
        v = relax<R, W>(cur[g], n, qn, qCur[g], p.lengths, p.base);
        changed |= v < cur[g];
        p.dst[lane + planeOffset(s)] = v;
      }
      sD[out][tb + 1][tx + 1] = v;  // +infinity outside the grid
      if constexpr (kQn) sQ[out][tb + 1][tx + 1] = qCur[g];
      if (hasRing) {
        sD[out][rb + 1][rx + 1] = ring[g];
        if constexpr (kQn) sQ[out][rb + 1][rx + 1] = qRing[g];
      }
      __syncthreads();
    }
#pragma unroll
    for (int g = 0; g < kGroup; ++g) {
      cur[g] = nCur[g], ring[g] = nRing[g], qCur[g] = nqCur[g], qRing[g] = nqRing[g];
    }
  }
  if (__syncthreads_or(changed) && t == 0) *p.changed = 1;
}

// ---- x sweeps --------------------------------------------------------------------------------

constexpr int kLy = 8, kLz = 4;                 // interior lines of a tile (one per lane)
constexpr int kHy = kLy + 2, kHz = kLz + 2;     // with the halo
constexpr int kLines = kHy * kHz;
constexpr int kChunk = 32;                      // x values per chunk
constexpr int kPitch = kChunk + 1;              // [0] = last value of the previous chunk
constexpr int kQPitch = 36;
static_assert(kLy * kLz == 32, "one warp per tile");

// Float offset of line (row = z + 1, col = y + 1) in shared memory: rows are padded by 30 floats
// so that the 32 interior lines start in 32 different banks (row·8 + col mod 32).
__device__ __forceinline__ int lineOffset(int row, int col) { return (row * kHy + col) * kPitch + row * 30; }
constexpr int kLineFloats = ((kHz - 1) * kHy + kHy) * kPitch + (kHz - 1) * 30;

struct LineSweep {
  const float* src;
  float* dst;
  const std::uint8_t* q;
  int nx, ny, nz;
  int direction;
  wdt::SweepLengths lengths;  // B = y, C = z
  float base;
  int* changed;
};

template <StepRule R, WeightRule W>
__global__ void __launch_bounds__(32) sweepAlongLines(LineSweep p) {
  __shared__ float sA[kLineFloats];
  __shared__ std::uint8_t sQ[kLines * kQPitch];
  const unsigned full = 0xffffffffu;
  const int lane = threadIdx.x;
  const int ly = lane % kLy, lz = lane / kLy;
  const int y = blockIdx.x * kLy + ly, z = blockIdx.y * kLz + lz;
  const bool inside = y < p.ny && z < p.nz;
  const int my = lineOffset(lz + 1, ly + 1);
  const int myQ = ((lz + 1) * kHy + ly + 1) * kQPitch;

  for (int l = lane; l < kLines; l += 32) {
    sA[lineOffset(l / kHy, l % kHy)] = kInf;
    sQ[l * kQPitch] = 0;
  }
  __syncwarp();

  bool changed = false;
  for (int x0 = 0; x0 < p.nx; x0 += kChunk) {
    const int steps = min(kChunk, p.nx - x0);
    const bool stepOk = lane < steps;
    const int xs = p.direction > 0 ? x0 + lane : p.nx - 1 - x0 - lane;
#pragma unroll 6
    for (int l = 0; l < kLines; ++l) {
      const int row = l / kHy, col = l % kHy;
      const int gy = blockIdx.x * kLy + col - 1, gz = blockIdx.y * kLz + row - 1;
      const bool ok = stepOk && gy >= 0 && gy < p.ny && gz >= 0 && gz < p.nz;
      const std::size_t i = ok ? std::size_t(xs) + std::size_t(p.nx) * (std::size_t(gy) + std::size_t(p.ny) * gz) : 0;
      sA[lineOffset(row, col) + 1 + lane] = ok ? __ldg(p.src + i) : kInf;
      sQ[l * kQPitch + 1 + lane] = ok ? __ldg(p.q + i) : 0;
    }
    __syncwarp();
    for (int s = 1; s <= steps; ++s) {
      if (inside) {
        float n[3][3];
        std::uint8_t qn[3][3];
#pragma unroll
        for (int dc = 0; dc < 3; ++dc) {
#pragma unroll
          for (int db = 0; db < 3; ++db) {
            n[dc][db] = sA[lineOffset(lz + dc, ly + db) + s - 1];
            qn[dc][db] = kNeedsNeighbourDensity<R, W> ? sQ[((lz + dc) * kHy + ly + db) * kQPitch + s - 1] : 0;
          }
        }
        const float c = sA[my + s];
        const float v = relax<R, W>(c, n, qn, sQ[myQ + s], p.lengths, p.base);
        changed |= v < c;
        sA[my + s] = v;
      }
      __syncwarp();
    }
    // Write the interior lines back, one coalesced row of the chunk per line.
#pragma unroll 4
    for (int i = 0; i < 32; ++i) {
      const int iy = blockIdx.x * kLy + i % kLy, iz = blockIdx.y * kLz + i / kLy;
      if (stepOk && iy < p.ny && iz < p.nz) {
        p.dst[std::size_t(xs) + std::size_t(p.nx) * (std::size_t(iy) + std::size_t(p.ny) * iz)] =
            sA[lineOffset(i / kLy + 1, i % kLy + 1) + 1 + lane];
      }
    }
    __syncwarp();
    for (int l = lane; l < kLines; l += 32) {
      const int o = lineOffset(l / kHy, l % kHy);
      sA[o] = sA[o + kChunk];
      sQ[l * kQPitch] = sQ[l * kQPitch + kChunk];
    }
    __syncwarp();
  }
  if (__any_sync(full, changed) && lane == 0) atomicOr(p.changed, 1);
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

template <StepRule R, WeightRule W>
void launchTyped(const SweepArgs& a, int axis, int direction, cudaStream_t stream) {
  const float sx = a.spacing[0], sy = a.spacing[1], sz = a.spacing[2];
  if (axis == 0) {
    LineSweep p{a.src, a.dst, a.density, a.nx, a.ny, a.nz, direction, wdt::axisSweepLengths(0, sx, sy, sz), a.baseCost,
                a.changed};
    const dim3 grid((a.ny + kLy - 1) / kLy, (a.nz + kLz - 1) / kLz);
    sweepAlongLines<R, W><<<grid, 32, 0, stream>>>(p);
  } else {
    const std::size_t sxy = std::size_t(a.nx) * a.ny;
    // y sweep: planes are xz (other axis z); z sweep: planes are xy (other axis y).
    const int nb = axis == 1 ? a.nz : a.ny, na = axis == 1 ? a.ny : a.nz;
    const std::size_t strideB = axis == 1 ? sxy : std::size_t(a.nx);
    const std::size_t strideA = axis == 1 ? std::size_t(a.nx) : sxy;
    PlaneSweep p{a.src, a.dst, a.density, a.nx, nb, na, strideB, strideA, direction, wdt::axisSweepLengths(axis, sx, sy, sz),
                 a.baseCost, a.changed};
    const dim3 grid((a.nx + kTileX - 1) / kTileX, (nb + kTileB - 1) / kTileB);
    sweepAlongPlanes<R, W><<<grid, dim3(kTileX, kTileB), 0, stream>>>(p);
  }
}

template <StepRule R>
void launchRule(const SweepArgs& a, int axis, int direction, cudaStream_t stream) {
  switch (a.weight) {
    case WeightRule::Density: return launchTyped<R, WeightRule::Density>(a, axis, direction, stream);
    case WeightRule::Uniform: return launchTyped<R, WeightRule::Uniform>(a, axis, direction, stream);
    case WeightRule::Gradient: return launchTyped<R, WeightRule::Gradient>(a, axis, direction, stream);
    case WeightRule::Ascent: return launchTyped<R, WeightRule::Ascent>(a, axis, direction, stream);
  }
}

}  // namespace

Status launchSweep(const SweepArgs& args, int axis, int direction, cudaStream_t stream) {
  // Only density weights tell the two step rules apart: uniform weights cost len under both
  // (½(1 + 1)·len = len exactly), gradient and ascent weights belong to the edge a → b and both
  // rules charge w(a→b)·len (as the CPU backend's step_cost.h does).
  if (args.rule == StepRule::Trapezoid && args.weight == WeightRule::Density) {
    launchTyped<StepRule::Trapezoid, WeightRule::Density>(args, axis, direction, stream);
  } else {
    launchRule<StepRule::Entering>(args, axis, direction, stream);
  }
  static const char* names[3][2] = {{"x-", "x+"}, {"y-", "y+"}, {"z-", "z+"}};
  return check(cudaGetLastError(), std::string("launch of the ") + names[axis][direction > 0] + " sweep kernel");
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
