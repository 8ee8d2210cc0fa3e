// Grow-from-seeds settings derived from the data, so that the defaults work at any voxel size and
// intensity scale (a 1 mm clinical CT in HU, a 0.1 mm µCT in plain uint8 intensities, an MR):
//
//   window   the values mapped to 0 … 1 (wdt/label_growth.h): CT in HU keeps the WDT's −1000 …
//            2000 HU; plain intensities use the dataset's histogram window (the 0.5th … 99.5th
//            percentiles, volume/intensity.h), so air sits near 0 and the densest bone near 1
//            whatever the scanner's scale.
//   base     the travel cost per mm, from the spacing and the data's step noise:
//            perVoxel = max(0.1 × the median |Δf| between face neighbours inside the body,
//            1/2560), base = perVoxel / voxelMm (voxelMm the geometric mean of the spacing). A step
//            costs base·len + |Δf| (wdt/step_cost.h): an edge costs its contrast once whatever the
//            voxel size, and one voxel of travel costs perVoxel plus the noise's |Δf| on every grid.
//            The 0.1 is empirical (bench/RESULTS.md "Grow at defaults"): the abdominal CT's organs
//            want a small base (at 3 mm the old floor of one grey level per voxel, 0.5× its noise,
//            cost the liver 0.09 Dice); the floor only keeps noise-free data's base above zero.
//   smoothing edge-preserving (bilateral, GrowthParams::edgeSigma) smoothing of 1 voxel whose edge
//            sigma is 3× the noise's sigma (from the step noise): noise's |Δf| summed along a path
//            — the part of travel that grows with every voxel — falls several-fold while edges of
//            more than ~6 noise sigmas (bone against soft tissue, organ against fat) stay sharp and
//            keep their contrast. On the abdominal CT it lifts the organs' mean Dice from 0.80 to
//            0.86; on the µCT-like volume the ossicles' labels take less of the neighbouring bone.
//            Noise-free data are not smoothed. The editor and seeds files ("smoothing") change it.
//
// The editor (desktop Segment window) and `anatomy-tutor segment` start from these and let the
// user change both; an explicit base or window always wins.
#pragma once

#include <array>
#include <optional>
#include <string>

#include "volume/intensity.h"
#include "volume/structure.h"
#include "wdt/label_growth.h"

namespace at::segment {

struct GrowthDefaults {
  GrowthParams params;        // gradient weights, the window and base below, backend auto
  double voxelMm = 1;         // geometric mean of the spacing
  double stepNoise = 0;       // median |Δf| between face neighbours inside the body (window units)
  double noiseSigmaStored = 0;  // the noise's sigma in stored values, from stepNoise
  std::array<double, 2> windowValues{};  // the window in the dataset's values (HU or intensities)
  // The "bone only" range limit the editor offers (GrowthParams::limitRange, off by default), in the
  // dataset's values: CT in HU from kBoneNoiseSigmas noise sigmas above soft tissue's peak (the
  // commonest 10 HU bin in −100 … 150 HU), kept within kBoneHuMin … kBoneHu, to the largest value
  // (the abdominal CT: peak 45 HU, sigma 25 HU → 119 HU; its vertebrae's median is 140 … 158 HU,
  // their quarter below 105 … 115, soft tissue's 95th percentile ≤ 67 HU). Vessels and kidneys
  // enhanced by contrast (200 … 400 HU) lie in that range too: there the user raises it. Plain intensities from kBoneHu
  // on a pseudo-HU scale set by two landmarks of the histogram — air (its 0.5th percentile, −1000
  // HU) and soft tissue (the commonest value above the valley that follows the midpoint of air and
  // the mean above air, 0 HU) — to the largest value. A scan without soft tissue (a dry skull) has no soft-tissue
  // peak: there the user sets the range.
  std::array<double, 2> boneRangeValues{};
  std::string summary;        // one line: "base 0.0123/mm (0.00123 per 0.1 mm voxel), window 0 … 255"
};

// The multiple of the step noise a voxel of travel costs by default (see above).
// 0.1: measured on the µCT-like phantom and the abdominal CT (bench/RESULTS.md, "Grow at
// defaults"): 1.0 and 0.3 let bone labels run into soft tissue and cost the organs Dice.
constexpr double kBaseNoiseMultiple = 0.1;
// The smallest per-voxel base, for noise-free data (a tenth of one grey level of 256 in the window).
constexpr double kMinBasePerVoxel = 1.0 / 2560.0;
// The default smoothing (sigma in voxels) and its edge sigma as a multiple of the noise's sigma.
constexpr double kSmoothingVoxels = 1.0;
constexpr double kEdgeSigmaNoiseMultiple = 3.0;

// The lower end of bone in HU for the "bone only" range of a CT (above): soft tissue's peak plus
// kBoneNoiseSigmas noise sigmas, within kBoneHuMin (cancellous bone of a 3 mm scan) … kBoneHu
// (compact bone; also the bone mark of plain intensities' pseudo-HU scale).
constexpr double kBoneNoiseSigmas = 3.0;
constexpr double kBoneHuMin = 100.0;
constexpr double kBoneHu = 300.0;

GrowthDefaults defaultGrowthSettings(const Volume& volume, const IntensityModel& intensity);

// `params` limited to the dataset values `values` (stored values inverted through the intensity
// model; limitRange set).
GrowthParams withRangeLimit(GrowthParams params, const IntensityModel& intensity, const std::array<double, 2>& values);

// The base per mm for `basePerVoxel` on this grid (basePerVoxel / voxelMm), and back: the editor
// shows the base per voxel, which means the same on every grid.
double basePerMm(double basePerVoxel, double voxelMm);
double basePerVoxelOf(double basePerMm, double voxelMm);

// The window in stored values for a window in the dataset's values (inverting slope/intercept).
std::array<float, 2> storedWindow(const IntensityModel& intensity, const std::array<double, 2>& values);

}  // namespace at::segment
