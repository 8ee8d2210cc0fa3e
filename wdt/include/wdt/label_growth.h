// Multi-label growth ("grow from seeds", ARCHITECTURE.md §3): seeds of two or more labels
// (background included); every voxel takes the label of the seed with the smallest weighted
// distance, computed by the WDT's sweeps with a label channel.
//
//   D(v) = min over seeds s and 26-connected paths s → v of Σ cost(step),   L(v) = label of that s.
//
// Step costs are the WDT's (wdt/step_cost.h, one stencil for every backend): usually the
// intensity difference (WeightRule::Gradient: w = base + |f(b) − f(a)|, f the windowed value),
// or the density (WeightRule::Density: w = base + f(b)), on any grid (lengths in mm).
//
// Distances are fixed point: each step's cost (the WDT's float cost) is scaled and rounded to an
// integer, and sums are exact (wdt/step_cost.h says why: with float sums, which label wins a tie
// could depend on the order of the relaxations). distances() returns them divided by the scale.
//
// Tie rule: where several seeds reach a voxel at the same (fixed-point) distance, the voxel takes
// the smallest label value among them (so background, usually label 0, wins ties). The field and
// the labels are the fixed point of
//   (D(v), L(v)) = min over neighbours u of (D(u) + cost(u → v), L(u))   (pairs compared
//   lexicographically), seeds fixed at (0, their label),
// which the exact reference (exactLabelGrowth, a multi-source Dijkstra with argmin labels)
// computes too: results equal it bit for bit, on the CPU and on the GPU.
//
// Interactive use: a LabelGrowth keeps its state between updates. When seeds are added, only the
// region the new seeds win is recomputed; when seeds are removed (or change label), the voxels
// that grew from them (on the CPU: the voxels a shortest path from them reaches; on the GPU, and
// after a cancelled update: every voxel of their labels) are reset and regrown from their
// surroundings. Work follows the changing front in bricks of 16³ voxels on both backends.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "volume/error.h"
#include "volume/grid.h"
#include "wdt/wdt.h"

namespace at {

struct GrowthSeed {
  std::size_t index = 0;     // voxel index on the volume grid: i + nx·(j + ny·k)
  std::uint16_t label = 0;   // the label value it spreads (0 is usually background)
  bool operator==(const GrowthSeed&) const = default;
};

struct GrowthParams {
  StepRule rule = StepRule::Entering;
  WeightRule weight = WeightRule::Gradient;  // Gradient: intensity difference; Density: density
  float windowMin = -1000.0f;  // stored value (HU for CT) mapped to 0 …
  float windowMax = 2000.0f;   // … and to 1 (the WDT's HU window, wdt.h)
  float baseCost = 0.05f;      // added to every weight; must be > 0 (a free step lets labels cross freely)
  // Gaussian blur (sigma in voxels, 0 … 8; 0: none) of the values before the window. Blurring a
  // monotone edge keeps the summed |Δf| of a path across it (its contrast) while noise's summed
  // |Δf| along a path falls several-fold, so noisy data (µCT) no longer makes travel as dear as
  // edges. segment/growth_settings.h picks it from the data.
  float smoothingVoxels = 0;
  // With smoothingVoxels > 0: 0 blurs with the Gaussian above; > 0 smooths preserving edges
  // (bilateral, radius ⌈2·smoothingVoxels⌉ ≤ 3 voxels): neighbours whose stored value differs by
  // more than a few edgeSigma (stored-value units) hardly count, so edges well above the noise stay
  // sharp — thin bone keeps its voxels — while the noise inside tissues averages out.
  float edgeSigma = 0;
  // Range limit ("bone only"): with limitRange, growth never enters a voxel whose stored value lies
  // outside rangeMin … rangeMax, nor passes through one; such voxels keep label 0 unless they are
  // seeds themselves (painted voxels keep their label, but do not spread from outside the range).
  // Limited growth runs on the CPU (the CUDA engine has no range limit; `cuda` is refused).
  bool limitRange = false;
  float rangeMin = 0;
  float rangeMax = 0;
  WdtBackend backend = WdtBackend::Auto;
  bool operator==(const GrowthParams&) const = default;  // every field equal (a kept growth still fits)
};

// The error names the field ("growth params: baseCost must be > 0, got 0").
Status validateGrowthParams(const GrowthParams& params);

struct GrowthStats {
  WdtBackend backendUsed = WdtBackend::Cpu;
  std::string device;          // "CPU (2 threads)" or the GPU's name
  std::string warning;         // e.g. why `auto` fell back to the CPU
  bool incremental = false;    // the update started from the previous state
  std::size_t seedsAdded = 0;  // seed voxels new or relabelled since the last update
  std::size_t seedsRemoved = 0;
  std::size_t voxelsReset = 0; // voxels sent back to +infinity because seeds of their label went
  std::size_t brickVisits = 0; // 16³ bricks swept (a brick may be visited in several rounds)
  int rounds = 0;
  bool converged = false;      // no brick is left to visit (false only when cancelled)
  bool cancelled = false;
  double msCompute = 0;        // the reset and the rounds (GPU: CUDA events), without transfers
  double msTotal = 0;          // the whole update, labels copied back to the host included
};

class GrowthEngine;

// A growth on one volume, kept between seed updates. Move-only.
class LabelGrowth {
 public:
  // Prepares a growth on `volume`: density bytes under the params' window; with the CUDA backend
  // they are uploaded and the state allocated on the device. Errors: an empty volume, invalid
  // params, `cuda` requested where no device exists (with `auto` that falls back to the CPU and
  // the first update's stats.warning says why).
  static Result<LabelGrowth> create(const Volume& volume, const GrowthParams& params);
  // As create, but the density bytes (the windowed, smoothed values: the set-up's dearest part) are
  // copied from `sameValues` where it was created on this same volume object (its voxels unchanged
  // since: the caller's promise) with the same window, smoothing and edge sigma, and keeps them on
  // the host (a CPU growth); otherwise, or with nullptr, they are computed. Either way the growth is
  // create's. For growths on one volume that differ in the range limit only (segment::RangedGrowth).
  static Result<LabelGrowth> create(const Volume& volume, const GrowthParams& params, const LabelGrowth* sameValues);
  ~LabelGrowth();
  LabelGrowth(LabelGrowth&&) noexcept;
  LabelGrowth& operator=(LabelGrowth&&) noexcept;
  LabelGrowth(const LabelGrowth&) = delete;
  LabelGrowth& operator=(const LabelGrowth&) = delete;

  // Replaces the seed set with `seeds` and brings distances and labels to the fixed point (from
  // scratch the first time, incrementally after). Errors: no seed, a seed outside the grid, a label
  // above 65534, one voxel seeded with two labels (the error names the voxel); the state is left
  // as it was. Cancellation (control.cancel) stops between rounds with stats.cancelled set; the
  // next update finishes the work left.
  Result<GrowthStats> update(const std::vector<GrowthSeed>& seeds, const WdtControl& control = {});

  const Geometry& grid() const;
  const GrowthParams& params() const;
  // The label of every voxel after the last update (all 0 before the first).
  const LabelMap& labels() const;
  // The weighted distance to each voxel's seed after the last update, copied from the backend.
  Result<FloatVolume> distances() const;

 private:
  struct State;
  explicit LabelGrowth(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

// The exact reference: a multi-source Dijkstra with argmin labels on the same 26-connected graph
// and step costs, with the same tie rule. For tests and checks, not for interaction.
struct GrowthResult {
  FloatVolume distances;
  LabelMap labels;
};
Result<GrowthResult> exactLabelGrowth(const Volume& volume, const std::vector<GrowthSeed>& seeds,
                                      const GrowthParams& params);

}  // namespace at
