// The exact reference of the multi-label growth: Dijkstra on the 26-connected grid over
// (distance, label) pairs compared lexicographically, with the growth's fixed-point step costs
// (wdt/step_cost.h). Costs are positive and sums exact, so popping the smallest pair first makes
// every voxel final when it pops: its distance the smallest path cost, its label the smallest label
// among the seeds with a path of that cost — the fixed point the engines' sweeps reach. A binary
// heap of packed keys (growthKey) is enough for tests and checks.
#include <cstdint>
#include <functional>
#include <limits>
#include <queue>
#include <vector>

#include "wdt/growth_engine.h"
#include "wdt/stencil.h"
#include "wdt/step_cost.h"
#include "neighbour_steps.h"

namespace at {

namespace {

using wdt::CostKernel;

template <CostKernel K>
void growExactly(const GrowthProblem& p, std::vector<std::uint64_t>& key) {
  const Dims d = p.grid.dims;
  const float sx = float(p.grid.spacingMm[0]), sy = float(p.grid.spacingMm[1]), sz = float(p.grid.spacingMm[2]);
  const std::vector<wdt::NeighbourStep> steps = wdt::neighbourSteps(d, sx, sy, sz);
  using Entry = std::pair<std::uint64_t, std::uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
  for (std::size_t i = 0; i < key.size(); ++i)
    if (wdt::growthKeyDistance(key[i]) == 0) heap.push({key[i], std::uint32_t(i)});
  while (!heap.empty()) {
    const auto [k, u] = heap.top();
    heap.pop();
    if (k != key[u]) continue;  // stale: u was lowered after this push
    const std::int32_t du = wdt::growthKeyDistance(k), lu = wdt::growthKeyLabel(k);
    const float fu = densityOf(p, u);
    const int x = int(u % std::uint32_t(d.x)), y = int(u / std::uint32_t(d.x) % std::uint32_t(d.y)),
              z = int(u / (std::uint32_t(d.x) * std::uint32_t(d.y)));
    for (const wdt::NeighbourStep& s : steps) {
      if (!d.contains(x + s.dx, y + s.dy, z + s.dz)) continue;
      const std::uint32_t v = std::uint32_t(std::int64_t(u) + s.delta);
      const std::int32_t cost =
          wdt::growthStepCost<K>(fu, densityOf(p, v), s.len, p.baseCost, p.scale);
      if (cost == wdt::kGrowthInf) continue;  // a blocked voxel: not entered, not left
      const std::uint64_t candidate = wdt::packGrowthKey(wdt::addGrowthCost(du, cost), lu);
      if (candidate < key[v]) {
        key[v] = candidate;
        heap.push({candidate, v});
      }
    }
  }
}

}  // namespace

Result<GrowthResult> exactGrowthOnProblem(const GrowthProblem& problem, const std::vector<GrowthSeed>& seeds) {
  const Dims d = problem.grid.dims;
  if (d.count() == 0 || problem.density.size() != d.count())
    return fail("growth exact: problem arrays do not match the grid " + d.toString());
  if (d.count() >= (std::size_t(1) << 32)) return fail("growth exact: grid " + d.toString() + " is too large");
  std::vector<std::uint64_t> key(d.count(), wdt::packGrowthKey(wdt::kGrowthInf, wdt::kNoLabel));
  for (const GrowthSeed& s : seeds) key[s.index] = wdt::packGrowthKey(0, s.label);
  wdt::withCostKernel(problem.kernel, [&]<CostKernel K>() { growExactly<K>(problem, key); });
  GrowthResult result;
  result.distances = FloatVolume(problem.grid, std::numeric_limits<float>::infinity());
  result.labels = LabelMap(problem.grid, 0);
  for (std::size_t i = 0; i < key.size(); ++i) {
    const std::int32_t dist = wdt::growthKeyDistance(key[i]), label = wdt::growthKeyLabel(key[i]);
    if (dist != wdt::kGrowthInf) result.distances.voxels[i] = float(dist) / problem.scale;
    result.labels.voxels[i] = label == wdt::kNoLabel ? 0 : std::uint16_t(label);
  }
  return result;
}

}  // namespace at
