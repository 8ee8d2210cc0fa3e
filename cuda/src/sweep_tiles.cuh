// Tiles of the sweep kernels (exact_sweep.cu, persistent_sweep.cu): the tile shapes, a group's
// arguments and the numbering of a tile's region voxels. Private to cuda/src.
#pragma once

#include <cuda_runtime.h>

#include <cstddef>
#include <cstdint>

#include "wdt/stencil.h"

namespace at::cuda {
namespace {

// Tile shape: TU × TV lanes of output per block (u contiguous), K planes per launch, T threads,
// at least MinBlocks blocks a multiprocessor (the register cap).
template <int TU_, int TV_, int T_, int MinBlocks_, int K_ = 8>
struct TileShape {
  static constexpr int TU = TU_, TV = TV_, K = K_, T = T_;
  static constexpr int MinBlocks = MinBlocks_;
  static constexpr int RU = TU + 2 * K, RV = TV + 2 * K;  // region: the tile and its widest halo
  static constexpr int RN = RU * RV;
  static constexpr int Core = TU * TV;
  static constexpr int CoreSlots = Core / T;               // a thread's first CoreSlots voxels are the tile's
  static constexpr int Slots = (RN + T - 1) / T;           // region voxels per thread
  static constexpr int Pitch = RU + 1;                     // odd row pitch: columns hit distinct banks
  static constexpr int PlaneFloats = RV * Pitch;
  static_assert(Core % T == 0, "the tile splits evenly among the threads");

  // Halo ring ρ (the voxels at Chebyshev distance ρ outside the tile): its voxel count, and the
  // halo number of its first voxel when the halo is numbered ring by ring from ring 1.
  static constexpr int ringSize(int ring) { return 2 * (TU + 2 * ring) + 2 * (TV + 2 * ring) - 4; }
  static constexpr int ringStart(int ring) {  // the sum of ringSize(1 … ring − 1)
    return (ring - 1) * (2 * TU + 2 * TV - 4) + 4 * ring * (ring - 1);
  }
  // Ring of halo voxel number n, K + 1 past the halo.
  static constexpr int haloRing(int n) {
    for (int ring = 1; ring <= K; ++ring) {
      if (n < ringStart(ring + 1)) return ring;
    }
    return K + 1;
  }
  // The last plane of a group at which any thread computes its slot k (slots hold region voxels
  // in ring order, so a slot's first voxel has its smallest ring): later planes' old values of
  // that slot are never loaded or kept.
  static constexpr int lastPlaneOfSlot(int k) {
    if (k < CoreSlots) return K;
    const int ring = haloRing(k * T - Core);
    return ring >= K ? 0 : K - ring;
  }
};
// The default tile. Measured on an H100 (bench/RESULTS.md): K = 8 beat K = 6 at 128³ and 256³
// (K = 10 and 12, with 3–4 planes loaded ahead, were slower still), 32 × 16 beat 32 × 8 and
// 64 × 16, and loading all K planes up front beat loading 3 or 4 planes ahead. Two blocks a
// multiprocessor (at most 64 registers a thread), so that the next group's blocks can become
// resident and load while this group's run.
using Shape = TileShape<32, 16, 512, 2>;
// The default tile in one-wave launches (the one-wave kernel, below, keeps densities in shared
// memory): 6 planes a group. Measured on an H200 (bench/RESULTS.md): 256³ 1.031 ms a pass
// against 1.105 with 8 planes (128³ 0.379 against 0.375); 1.54× the tile's voxels computed.
using OneWaveShape = TileShape<32, 16, 512, 2, 6>;
// The large tile, for planes whose default tiles would need more than one wave (e.g. 512³ on an
// H200: 512 default blocks on 132 multiprocessors, 128 large ones; 1024³: 2048 and 512): one
// block of 1024 threads a multiprocessor, with the one-wave kernel's densities in shared memory,
// and fewer voxels computed (1.25× the tile's over a group of 6 planes, against 1.79× for the
// default tile's 8). Measured on an H200 (bench/RESULTS.md): 512³ 5.30 ms a pass with 4 or 6
// planes, 5.31 with 5, 5.75 with 8 (48 bytes spilled at 64 registers), 7.15 with the default
// tile; in several waves, 768³ 20.5 against 25.1 and 1024³ 43.6 against 57.9.
using LargeShape = TileShape<64, 32, 1024, 1, 6>;
static_assert(Shape::ringStart(3) == Shape::ringSize(1) + Shape::ringSize(2), "ringStart sums the ring sizes");
static_assert(Shape::ringStart(Shape::K + 1) == Shape::RN - Shape::Core, "the rings make up the halo");
static_assert(LargeShape::ringStart(LargeShape::K + 1) == LargeShape::RN - LargeShape::Core,
              "the rings make up the halo");
static_assert(OneWaveShape::ringStart(OneWaveShape::K + 1) == OneWaveShape::RN - OneWaveShape::Core,
              "the rings make up the halo");

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
  unsigned long long* lowered;
};

// Region voxel number n (the tile first, row by row; then the halo ring by ring outwards, each
// ring's top row, bottom row, left column, right column). ring = K + 1 marks n past the region.
struct RegionVoxel {
  int ru, rv, ring;
};

template <class S>
__device__ __forceinline__ RegionVoxel regionVoxel(int n) {
  if (n < S::Core) return {S::K + n % S::TU, S::K + n / S::TU, 0};
  if (n >= S::RN) return {0, 0, S::K + 1};
  n -= S::Core;
  int ring = 1, first = 0;  // haloRing(n) and ringStart(ring), found in one walk
  for (; ring < S::K && n >= first + S::ringSize(ring); ++ring) first += S::ringSize(ring);
  const int o = n - first, w = S::TU + 2 * ring, h = S::TV + 2 * ring, left = S::K - ring, top = S::K - ring;
  if (o < w) return {left + o, top, ring};
  if (o < 2 * w) return {left + o - w, top + h - 1, ring};
  if (o < 2 * w + h - 2) return {left, top + 1 + o - 2 * w, ring};
  return {left + w - 1, top + 1 + o - 2 * w - (h - 2), ring};
}

}  // namespace
}  // namespace at::cuda
