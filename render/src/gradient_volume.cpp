#include "render/gradient_volume.h"

#include <algorithm>
#include <cmath>

#include "core/parallel_rows.h"

namespace at::render {

namespace {

constexpr float kBinomial[5] = {1.0f / 16, 4.0f / 16, 6.0f / 16, 4.0f / 16, 1.0f / 16};

std::int16_t snorm16(float v) { return std::int16_t(std::lround(std::clamp(v, -1.0f, 1.0f) * 32767.0f)); }

}  // namespace

GradientVolume computeGradientVolume(const Volume& volume, int threads) {
  GradientVolume out;
  out.grid = volume.geometry;
  if (volume.empty()) return out;
  const Dims& d = volume.dims();
  const std::size_t slice = std::size_t(d.x) * std::size_t(d.y);
  // Smoothed along x and y, slice by slice.
  std::vector<float> xy(d.count());
  forEachBlockInParallel(d.z, [&](int k0, int k1) {
    std::vector<float> row(std::size_t(d.x) * std::size_t(d.y));
    for (int k = k0; k < k1; ++k) {
      const std::int16_t* src = volume.voxels.data() + slice * std::size_t(k);
      for (int j = 0; j < d.y; ++j)
        for (int i = 0; i < d.x; ++i) {
          float s = 0;
          for (int m = -2; m <= 2; ++m)
            s += kBinomial[m + 2] * float(src[std::size_t(j) * std::size_t(d.x) + std::size_t(std::clamp(i + m, 0, d.x - 1))]);
          row[std::size_t(j) * std::size_t(d.x) + std::size_t(i)] = s;
        }
      float* dst = xy.data() + slice * std::size_t(k);
      for (int j = 0; j < d.y; ++j)
        for (int i = 0; i < d.x; ++i) {
          float s = 0;
          for (int m = -2; m <= 2; ++m)
            s += kBinomial[m + 2] * row[std::size_t(std::clamp(j + m, 0, d.y - 1)) * std::size_t(d.x) + std::size_t(i)];
          dst[std::size_t(j) * std::size_t(d.x) + std::size_t(i)] = s;
        }
    }
  }, threads);
  // Smoothed along z on the fly (a window of three smoothed slices), then central differences.
  out.texels.resize(d.count());
  const double sx = volume.geometry.spacingMm[0], sy = volume.geometry.spacingMm[1], sz = volume.geometry.spacingMm[2];
  const Mat3& dir = volume.geometry.direction;
  const double voxelMm = std::cbrt(sx * sy * sz);
  forEachBlockInParallel(d.z, [&](int k0, int k1) {
    std::vector<float> window[3];
    const auto smoothZ = [&](int k, std::vector<float>& dst) {
      dst.resize(slice);
      for (std::size_t v = 0; v < slice; ++v) {
        float s = 0;
        for (int m = -2; m <= 2; ++m) s += kBinomial[m + 2] * xy[slice * std::size_t(std::clamp(k + m, 0, d.z - 1)) + v];
        dst[v] = s;
      }
    };
    smoothZ(std::max(k0 - 1, 0), window[0]);
    smoothZ(k0, window[1]);
    for (int k = k0; k < k1; ++k) {
      smoothZ(std::min(k + 1, d.z - 1), window[2]);
      const std::vector<float>& below = window[0];
      const std::vector<float>& here = window[1];
      const std::vector<float>& above = window[2];
      // One-sided at the volume's faces, as the clamped reads give: the difference spans fewer voxels.
      const float zSpan = float((std::min(k + 1, d.z - 1) - std::max(k - 1, 0)));
      for (int j = 0; j < d.y; ++j) {
        const int jm = std::max(j - 1, 0), jp = std::min(j + 1, d.y - 1);
        for (int i = 0; i < d.x; ++i) {
          const int im = std::max(i - 1, 0), ip = std::min(i + 1, d.x - 1);
          const std::size_t v = std::size_t(j) * std::size_t(d.x) + std::size_t(i);
          // Index-space derivatives (HU per voxel).
          const float gi = (here[std::size_t(j) * std::size_t(d.x) + std::size_t(ip)] -
                            here[std::size_t(j) * std::size_t(d.x) + std::size_t(im)]) / float(ip - im > 0 ? ip - im : 1);
          const float gj = (here[std::size_t(jp) * std::size_t(d.x) + std::size_t(i)] -
                            here[std::size_t(jm) * std::size_t(d.x) + std::size_t(i)]) / float(jp - jm > 0 ? jp - jm : 1);
          const float gk = zSpan > 0 ? (above[v] - below[v]) / zSpan : 0.0f;
          // Patient-frame gradient in HU per mm (the index derivatives per mm, rotated by the
          // direction cosines), times the voxel size: HU per voxel.
          const double a = gi / sx, b = gj / sy, c = gk / sz;
          std::array<std::int16_t, 4>& t = out.texels[slice * std::size_t(k) + v];
          t[0] = std::int16_t(volume.voxels[slice * std::size_t(k) + v] == -32768 ? -32767
                                                                                   : volume.voxels[slice * std::size_t(k) + v]);
          for (int r = 0; r < 3; ++r) {
            const double p = (dir.m[std::size_t(r)][0] * a + dir.m[std::size_t(r)][1] * b + dir.m[std::size_t(r)][2] * c) * voxelMm;
            t[std::size_t(r + 1)] = snorm16(float(p / GradientVolume::kMaxHuPerVoxel));
          }
        }
      }
      std::swap(window[0], window[1]);
      std::swap(window[1], window[2]);
    }
  }, threads);
  return out;
}

}  // namespace at::render
