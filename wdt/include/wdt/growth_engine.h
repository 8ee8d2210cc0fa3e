// The backend-facing side of the multi-label growth (label_growth.h): what the front end hands a
// CPU or CUDA engine. Engines keep the state of one growth — a (distance, label) key per voxel
// (packGrowthKey, wdt/step_cost.h) and the density bytes — and relax it in rounds over bricks of
// kGrowthBrickEdge³ voxels:
//
//   A visit loads a brick and a one-voxel halo, sweeps it x+ x− y+ y− z+ z− with
//   relaxLabelledVoxel (the CPU repeats that while a pass changes something), stores the voxels
//   that decreased, queues the neighbour bricks whose halo holds a decreased voxel, and queues
//   itself again if its last pass still changed something, until no brick is queued. The GPU
//   visits all queued bricks in rounds; the CPU takes them from a priority queue.
//
// Keys only ever decrease and each is moved by one 64-bit load or store, so a visit that reads a
// neighbour's halo while that neighbour is being written sees an old or a new pair, never a torn
// one; a new value queues the reader again. Any such order of relaxations ends at the one fixed
// point (costs > 0 and sums exact: fixed-point distances), so both engines give the same bits as
// the exact reference.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "volume/error.h"
#include "volume/grid.h"
#include "wdt/label_growth.h"
#include "wdt/step_cost.h"

namespace at {

constexpr int kGrowthBrickEdge = 16;

struct GrowthProblem {
  Geometry grid;
  std::vector<std::uint8_t> density;  // densityByte() per voxel under the params' window
  wdt::CostKernel kernel = wdt::CostKernel::EdgeGradient;
  float baseCost = 0.05f;
  float scale = 1.0f;  // fixed-point units per unit of cost (growthStepCost, wdt/step_cost.h)
  // Empty, or one byte per voxel: non-zero where growth may not enter (GrowthParams' range limit).
  // Only the CPU engine and the exact reference read it (the front end picks the CPU for it).
  std::vector<std::uint8_t> blocked;
};

// The density an engine relaxes voxel v with: wdt::kBlockedDensity where blocked, else the byte's.
inline float densityOf(const GrowthProblem& p, std::size_t v) {
  return !p.blocked.empty() && p.blocked[v] ? wdt::kBlockedDensity : wdt::densityFromByte(p.density[v]);
}

// One update's change of the seeds, worked out by the front end. Applied in this order: every
// voxel whose label is in `resetLabels` goes back to (+infinity, kNoLabel); then every seed of
// `writeSeeds` is set to (0, label). The bricks holding a voxel either step changed are queued.
// An engine whose resetsGrownFromRemovedSeeds() is true gets `removedSeeds` instead of
// `resetLabels` (then empty): it resets only the voxels whose pair came from those seeds (the
// seeds themselves and the voxels a shortest path from them reaches), before writing `writeSeeds`
// (then only the new and relabelled seeds).
struct GrowthChange {
  std::vector<std::uint16_t> resetLabels;  // sorted, unique
  std::vector<GrowthSeed> writeSeeds;      // new and relabelled seeds, and the kept seeds of reset labels
  std::vector<GrowthSeed> removedSeeds;    // seeds removed or relabelled, with their old labels
  bool fromScratch = false;                // the state is fresh: every voxel starts at +infinity
};

class GrowthEngine {
 public:
  virtual ~GrowthEngine() = default;
  // Applies `change` and visits bricks until none is queued or control.cancel is set (the CPU looks
  // before each visit, the GPU before its rounds start; queued bricks then stay queued for the next
  // call). Fills stats' backend, device, voxelsReset, brickVisits, rounds (GPU), converged,
  // cancelled and msCompute.
  virtual Status apply(const GrowthChange& change, const WdtControl& control, GrowthStats& stats) = 0;
  // Whether the engine takes GrowthChange::removedSeeds (a seed edit then costs what it changes,
  // not a regrowth of every voxel of the edited labels).
  virtual bool resetsGrownFromRemovedSeeds() const { return false; }
  // Copies the labels (kNoLabel as 0) or the distances (fixed point / scale; +infinity where no seed
  // reached) of every voxel out.
  virtual Status readLabels(LabelMap& out) = 0;
  virtual Status readDistances(FloatVolume& out) = 0;
  // The density bytes the engine grows on (GrowthProblem::density), where it keeps them on the
  // host (the CPU engine); nullptr where it does not (the GPU engine keeps them on the device).
  virtual const std::vector<std::uint8_t>* hostDensity() const { return nullptr; }
};

// The CPU engine: bricks of a round shared among the cores.
std::unique_ptr<GrowthEngine> makeCpuGrowthEngine(GrowthProblem problem);

// The exact reference on a problem (exactLabelGrowth without the front end's checks: the seeds
// must lie on the grid, one label per voxel).
Result<GrowthResult> exactGrowthOnProblem(const GrowthProblem& problem, const std::vector<GrowthSeed>& seeds);

}  // namespace at
