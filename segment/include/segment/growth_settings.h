// Grow-from-seeds settings derived from the data, so that the defaults work at any voxel size and
// intensity scale (a 1 mm clinical CT in HU, a 0.1 mm µCT in plain uint8 intensities, an MR):
//
//   window   the values mapped to 0 … 1 (wdt/label_growth.h): CT in HU keeps the WDT's −1000 …
//            2000 HU; plain intensities use the dataset's histogram window (the 0.5th … 99.5th
//            percentiles, volume/intensity.h), so air sits near 0 and the densest bone near 1
//            whatever the scanner's scale.
//   base     the cost per mm added to every step, from the spacing and the data's step noise:
//            perVoxel = max(0.1 × the median |Δf| between face neighbours inside the body,
//            1/256), base = perVoxel / voxelMm (voxelMm the geometric mean of the spacing). A step
//            costs (base + |Δf|)·len (wdt/step_cost.h), so the travel part of one voxel step is
//            perVoxel whatever the spacing while an edge's part shrinks with the voxel; the rule
//            is empirical — measured on a µCT-like 0.1 mm phantom in uint8 intensities and the
//            3 mm abdominal CT (bench/RESULTS.md "Grow at defaults"): better than the old fixed
//            0.05 per mm on the µCT's bones (a few points) and on the organs (Dice +0.06 … 0.22) —
//            an empirical rule, not a derived invariance.
//   smoothing none by default (GrowthParams::smoothingVoxels): a blur of one voxel helped the
//            abdominal CT's organs but cost the µCT's thin ossicles; the editor offers it.
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
  std::array<double, 2> windowValues{};  // the window in the dataset's values (HU or intensities)
  std::string summary;        // one line: "base 0.0123/mm (0.00123 per 0.1 mm voxel), window 0 … 255"
};

// The multiple of the step noise a voxel of travel costs by default (see above).
// 0.1: measured on the µCT-like phantom and the abdominal CT (bench/RESULTS.md, "Grow at
// defaults"): 1.0 and 0.3 let bone labels run into soft tissue; at 0.1 the floor below rules.
constexpr double kBaseNoiseMultiple = 0.1;
// The smallest per-voxel base, for noise-free data (one grey level of 256 in the window).
constexpr double kMinBasePerVoxel = 1.0 / 256.0;

GrowthDefaults defaultGrowthSettings(const Volume& volume, const IntensityModel& intensity);

// The base per mm for `basePerVoxel` on this grid (basePerVoxel / voxelMm), and back: the editor
// shows the base per voxel, which means the same on every grid.
double basePerMm(double basePerVoxel, double voxelMm);
double basePerVoxelOf(double basePerMm, double voxelMm);

// The window in stored values for a window in the dataset's values (inverting slope/intercept).
std::array<float, 2> storedWindow(const IntensityModel& intensity, const std::array<double, 2>& values);

}  // namespace at::segment
