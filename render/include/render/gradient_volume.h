// What the ray caster samples per voxel, precomputed once per volume: the HU and the gradient of a
// lightly smoothed copy of them, for shading and for the context's surface opacity (ARCHITECTURE.md
// §4, "context drawn as surfaces").
//
// The gradient is taken of the HU smoothed by a separable binomial [1 4 6 4 1]/16 per axis
// (σ = 1 voxel), so CT noise does not turn into grain in the shading or flicker in the surface
// opacity. Each voxel is four signed 16-bit values (the GL texture RGBA16_SNORM, one trilinear
// fetch per sample):
//   [0]  the HU themselves (not smoothed), as HU / 32767;
//   [1..3] the gradient in the patient frame (LPS), in HU per mm times the voxel size h (the
//        geometric mean of the spacings), over kMaxHuPerVoxel — "HU per voxel", so a preset's edge
//        thresholds mean the same on 0.2 mm and 3 mm grids. Its length is the edge strength, its
//        direction the shading normal; trilinear filtering of the vector (rather than of unit
//        normals) keeps both right between voxels.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "volume/grid.h"

namespace at::render {

struct GradientVolume {
  static constexpr float kMaxHuPerVoxel = 4000.0f;  // stronger edges saturate (per component)

  Geometry grid;                                   // the volume's grid
  std::vector<std::array<std::int16_t, 4>> texels;  // dims.count(), i contiguous

  bool empty() const { return texels.empty(); }
  // HU and edge strength (HU per voxel) of texel values as the GPU decodes them (snorm: v / 32767).
  static float decodeHu(float snorm) { return snorm * 32767.0f; }
  static float strengthOf(float gx, float gy, float gz) {
    return std::sqrt(gx * gx + gy * gy + gz * gz) * kMaxHuPerVoxel;
  }
  float strengthAt(std::size_t index) const {
    const auto& t = texels[index];
    return strengthOf(float(t[1]) / 32767.0f, float(t[2]) / 32767.0f, float(t[3]) / 32767.0f);
  }
};

// Threads: at most this many (0 = hardware concurrency). Deterministic (the same bytes for any
// thread count).
GradientVolume computeGradientVolume(const Volume& volume, int threads = 0);

}  // namespace at::render
