// Weighted distance transform (ARCHITECTURE.md §3, the paper's §3 and §5).
//
//   D(g) = min over 26-connected voxel paths from the seed set W to g of Σ cost(step),  D = 0 on W.
//
// Step cost: `Entering` (the paper) w(b)·|step|; `Trapezoid` ½(w(a)+w(b))·|step| (the rule of
// scikit-image's MCP_Geometric). |step| is physical: 1, √2, √3 voxel steps scaled by the spacing
// in millimetres per axis. Weights come from the CT through `weightsFromVolume` (stencil.h).
// Distances are float32 millimetre-weighted path costs; unreachable voxels hold +infinity.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/error.h"
#include "volume/grid.h"

namespace at {

enum class StepRule { Entering, Trapezoid };
// Density: w = base + window(HU) (0..1, quantised to 8 bits). Uniform: w = 1 everywhere (the
// non-weighted distance the paper compares against). Gradient: a step a → b of length len costs
// base·len + |f(b) − f(a)|; Ascent: base·len + max(f(b) − f(a), 0) (the paper's other options;
// f = window(HU)). In both, travel costs base per mm and crossing an edge costs its contrast once,
// whatever the voxel size or the step's direction (wdt/step_cost.h).
enum class WeightRule { Density, Uniform, Gradient, Ascent };
enum class WdtBackend { Auto, Cpu, Cuda };

const char* toString(StepRule rule);
const char* toString(WeightRule rule);
const char* toString(WdtBackend backend);
Result<StepRule> parseStepRule(const std::string& text);
Result<WeightRule> parseWeightRule(const std::string& text);
Result<WdtBackend> parseBackend(const std::string& text);

struct WdtParams {
  StepRule rule = StepRule::Entering;
  WeightRule weight = WeightRule::Density;
  float huMin = -1000.0f;   // window: HU at or below → density 0
  float huMax = 2000.0f;    // HU at or above → density 1
  float baseCost = 0.02f;   // added to every weight so air is cheap but never free
  int passes = 2;           // fixed number of passes (one pass = sweeps x+ x− y+ y− z+ z−)
  bool converge = false;    // repeat passes until one changes nothing (at most maxPasses)
  int maxPasses = 64;
  int downsample = 1;       // compute on a grid coarser by this factor per axis (1 = full)
  WdtBackend backend = WdtBackend::Auto;
};

// Checks the params: passes >= 1, downsample >= 1, huMax > huMin, baseCost >= 0 (and finite),
// maxPasses >= 1. The error names the field ("WDT params: passes must be >= 1, got 0").
Status validateWdtParams(const WdtParams& params);

// A distance field on its own grid (the volume's, or a coarser one when downsampled: same
// physical extent, spacing × factor, origin moved to the block centres).
struct DistanceField {
  FloatVolume distances;   // +infinity where unreachable
  int downsample = 1;
};

struct WdtStats {
  // "sweeps": whole-volume passes only (passesRun, msPerPass). "sweeps+bricks" (the CUDA backend's
  // converge mode on grids over 128³) or "bricks" (the same with no pass first, its default up to
  // 128³): passes, then `rounds` over the 16³ bricks that still change; the field is the same
  // fixed point the converged sweeps reach.
  std::string scheme = "sweeps";
  int passesRun = 0;
  int rounds = 0;
  bool converged = false;      // the last pass changed nothing (bricks: no brick left active)
  bool cancelled = false;
  std::vector<double> msPerPass;
  double msCompute = 0;        // the passes or rounds alone (GPU: CUDA events), without set-up and transfers
  double msTotal = 0;          // including weight preparation and transfers
  WdtBackend backendUsed = WdtBackend::Cpu;
  std::string device;          // "CPU (2 threads)" or the GPU's name
  std::string warning;         // e.g. why `auto` fell back to the CPU; empty if none
};

struct WdtResult {
  DistanceField field;
  WdtStats stats;
};

// Progress after each pass: (passes done, passes planned or maxPasses). Called on the computing
// thread. Cancellation: set *cancel to true from any thread; the call returns after the current
// sweep with stats.cancelled = true and the partial field (never below the exact distances).
struct WdtControl {
  std::function<void(int, int)> progress;
  const std::atomic<bool>* cancel = nullptr;
};

// Computes the field from the seed voxels (mask != 0). Errors: mask on another grid, empty mask,
// invalid params (passes < 1, downsample < 1, huMax <= huMin, baseCost < 0), `cuda` requested
// where no device exists or a CUDA call fails (with `auto` those fall back to the CPU and set
// stats.warning instead).
Result<WdtResult> computeWdt(const Volume& volume, const Mask& seeds, const WdtParams& params,
                             const WdtControl& control = {});

// Exact reference: Dijkstra (a bucket queue, exact for these float costs) on the same 26-connected
// graph, rule and weights, on the full grid. For tests and --check, not for interaction.
Result<FloatVolume> exactWdt(const Volume& volume, const Mask& seeds, const WdtParams& params);

// Upsamples a (possibly downsampled) field to `target` trilinearly in the patient frame.
FloatVolume upsampleField(const DistanceField& field, const Geometry& target);

// Accuracy of `field` against `exact` over reachable non-seed voxels (exact finite and > 0).
struct WdtAccuracy {
  double meanRelErr = 0, p99RelErr = 0, maxRelErr = 0;
  double exactFraction = 0;     // share within 1e-5 relative
  std::size_t belowExact = 0;   // voxels with D < exact·(1 − 1e-5): must be 0
  std::size_t compared = 0;
};
WdtAccuracy compareToExact(const FloatVolume& field, const FloatVolume& exact);

}  // namespace at
