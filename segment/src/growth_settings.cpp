// Grow-from-seeds defaults from the data (growth_settings.h).
#include "segment/growth_settings.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "volume/intensity_landmarks.h"
#include "wdt/problem.h"
#include "wdt/wdt.h"

namespace at::segment {

namespace {

// The median |Δ density byte| between face neighbours where either voxel is denser than 5 % of the
// window (air saturated at 0 on both sides says nothing about the tissue's noise), in window units.
double medianStepNoise(const Volume& volume, const std::array<float, 2>& window) {
  WdtParams p;
  p.huMin = window[0];
  p.huMax = window[1];
  const std::vector<std::uint8_t> lut = densityTable(p);
  const Dims d = volume.dims();
  std::vector<std::uint64_t> histogram(256, 0);
  std::uint64_t total = 0;
  const auto byteAt = [&](std::size_t v) { return lut[std::size_t(volume.voxels[v] + 32768)]; };
  const std::size_t strides[3] = {1, std::size_t(d.x), std::size_t(d.x) * std::size_t(d.y)};
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const std::size_t v = d.index(i, j, k);
        const int a = byteAt(v);
        const bool inside[3] = {i + 1 < d.x, j + 1 < d.y, k + 1 < d.z};
        for (int axis = 0; axis < 3; ++axis) {
          if (!inside[axis]) continue;
          const int b = byteAt(v + strides[axis]);
          if (std::max(a, b) <= 12) continue;
          ++histogram[std::size_t(std::abs(a - b))];
          ++total;
        }
      }
  if (total == 0) return 0;
  std::uint64_t seen = 0;
  for (std::size_t level = 0; level < histogram.size(); ++level) {
    seen += histogram[level];
    if (2 * seen >= total) return double(level) / 255.0;
  }
  return 1;
}

// The "bone only" range in stored values (growth_settings.h).
std::array<float, 2> boneRangeStored(const Volume& volume, const IntensityModel& intensity, double noiseSigmaStored) {
  const std::vector<std::uint64_t> histogram = valueHistogram(volume.voxels);
  int top = -32768;
  for (std::int16_t v : volume.voxels) top = std::max(top, int(v));
  if (intensity.hounsfield()) {
    // Soft tissue's peak: the commonest 10 HU bin in −100 … 150 HU; bone starts kBoneNoiseSigmas
    // noise sigmas above it, kept within kBoneHuMin … kBoneHu.
    std::vector<std::uint64_t> bins(25, 0);
    for (std::size_t v = 0; v < histogram.size(); ++v) {
      const double hu = intensity.valueOf(float(double(v) - 32768.0));
      if (hu >= -100 && hu < 150) bins[std::size_t((hu + 100) / 10)] += histogram[v];
    }
    const std::size_t peakBin = std::size_t(std::max_element(bins.begin(), bins.end()) - bins.begin());
    const double softHu = -100.0 + 10.0 * double(peakBin) + 5.0;
    const double sigmaHu = noiseSigmaStored * std::abs(intensity.slope);
    const double boneHu = std::clamp(softHu + kBoneNoiseSigmas * sigmaHu, kBoneHuMin, kBoneHu);
    const float low = float(std::ceil((boneHu - intensity.intercept) / intensity.slope));
    return {low, std::max(low, float(top))};
  }
  // Plain intensities: a pseudo-HU scale from two landmarks, air (the histogram window's low end,
  // −1000 HU) and soft tissue (volume/intensity_landmarks.h: the commonest value above the valley
  // after the body's threshold, 0 HU), then kBoneHu on that scale.
  const int air = int(intensity.window[0]);
  const SoftTissueLandmarks landmarks = softTissueLandmarks(histogram, air);
  const double softValue = landmarks.softTissue;
  const float low = float(softValue + (softValue - air) * kBoneHu / 1000.0);
  return {std::ceil(low), std::max(std::ceil(low), float(top))};
}

}  // namespace

GrowthParams withRangeLimit(GrowthParams params, const IntensityModel& intensity, const std::array<double, 2>& values) {
  const std::array<float, 2> stored = storedWindow(intensity, values);
  params.limitRange = true;
  params.rangeMin = std::min(stored[0], stored[1]);
  params.rangeMax = std::max(stored[0], stored[1]);
  return params;
}

double basePerMm(double basePerVoxel, double voxelMm) { return basePerVoxel / voxelMm; }
double basePerVoxelOf(double basePerMmValue, double voxelMm) { return basePerMmValue * voxelMm; }

std::array<float, 2> storedWindow(const IntensityModel& m, const std::array<double, 2>& values) {
  return {float((values[0] - m.intercept) / m.slope), float((values[1] - m.intercept) / m.slope)};
}

GrowthDefaults defaultGrowthSettings(const Volume& volume, const IntensityModel& intensity) {
  GrowthDefaults out;
  const auto& s = volume.geometry.spacingMm;
  out.voxelMm = std::cbrt(s[0] * s[1] * s[2]);
  if (!(out.voxelMm > 0)) out.voxelMm = 1;
  std::array<float, 2> window = intensity.window;  // stored values: −1000 … 2000 HU, or the histogram's
  if (!(window[1] > window[0])) window[1] = window[0] + 1;
  out.params.windowMin = window[0];
  out.params.windowMax = window[1];
  out.windowValues = {intensity.valueOf(window[0]), intensity.valueOf(window[1])};
  out.stepNoise = medianStepNoise(volume, window);
  const double perVoxel = std::max(kBaseNoiseMultiple * out.stepNoise, kMinBasePerVoxel);
  out.params.baseCost = float(basePerMm(perVoxel, out.voxelMm));
  // The noise's sigma in stored values: the median |a − b| of two independent N(0, σ²) samples is
  // 0.954 σ (0.6745·√2).
  out.noiseSigmaStored = out.stepNoise * double(window[1] - window[0]) / 0.954;
  if (out.noiseSigmaStored > 0) {
    out.params.smoothingVoxels = float(kSmoothingVoxels);
    out.params.edgeSigma = float(kEdgeSigmaNoiseMultiple * out.noiseSigmaStored);
  }
  const std::array<float, 2> bone = boneRangeStored(volume, intensity, out.noiseSigmaStored);
  out.boneRangeValues = {intensity.valueOf(bone[0]), intensity.valueOf(bone[1])};
  char text[320];
  std::snprintf(text, sizeof text,
                "base %.4g/mm (%.4g per %.3g mm voxel; step noise %.4g), smoothing %g voxel (edge sigma %.3g), "
                "window %g … %g %s, bone only: %g … %g",
                out.params.baseCost, perVoxel, out.voxelMm, out.stepNoise, double(out.params.smoothingVoxels),
                double(out.params.edgeSigma), out.windowValues[0], out.windowValues[1],
                intensity.unitName(), out.boneRangeValues[0], out.boneRangeValues[1]);
  out.summary = text;
  return out;
}

}  // namespace at::segment
