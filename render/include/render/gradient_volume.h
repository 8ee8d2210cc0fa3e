// Surface normals and edge strength of a CT volume, precomputed once per volume for shading and
// for the context's surface opacity (ARCHITECTURE.md §4, "context drawn as surfaces").
//
// The gradient is taken of a lightly smoothed copy of the HU (a separable binomial [1 4 6 4 1]/16
// per axis, σ = 1 voxel), so CT noise does not turn into grain in the shading or flicker in the
// surface opacity. Per voxel it keeps, packed as four signed bytes (the GL texture RGBA8_SNORM):
//   xyz: the unit gradient direction in the patient frame (LPS), from derivatives in HU per mm;
//        zero where the smoothed HU is flat.
//   w:   the edge strength g in HU per voxel (the index-space gradient norm, so a preset's
//        thresholds mean the same on 0.2 mm and 3 mm grids), encoded as
//        w = round(127 · sqrt(min(g, kMaxHuPerVoxel) / kMaxHuPerVoxel)): the square root keeps
//        precision at the weak edges where surface thresholds lie.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "volume/grid.h"

namespace at::render {

struct GradientVolume {
  static constexpr float kMaxHuPerVoxel = 4000.0f;  // stronger edges saturate

  Geometry grid;                                  // the volume's grid
  std::vector<std::array<std::int8_t, 4>> texels;  // dims.count(), i contiguous

  bool empty() const { return texels.empty(); }
  // Edge strength (HU per voxel) of a w byte as the GPU decodes it (snorm: w / 127).
  static float decodeStrength(float wSnorm) { return wSnorm * wSnorm * kMaxHuPerVoxel; }
  float strengthAt(std::size_t index) const { return decodeStrength(float(texels[index][3]) / 127.0f); }
};

// Threads: 0 = hardware concurrency. Deterministic (the same bytes for any thread count).
GradientVolume computeGradientVolume(const Volume& volume, int threads = 0);

}  // namespace at::render
