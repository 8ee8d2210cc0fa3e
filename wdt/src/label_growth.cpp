// LabelGrowth: the front end of the multi-label growth. Checks seeds, works out what changed since
// the last update (which labels to reset, which seeds to write) and hands that to the CPU or CUDA
// engine (growth_engine.h), falling back from CUDA to the CPU under `auto` as computeWdt does.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <set>
#include <string>

#include "growth_smoothing.h"
#include "wdt/growth_engine.h"
#include "wdt/label_growth.h"
#include "wdt/problem.h"

#if defined(AT_HAVE_CUDA)
#include "cuda/label_growth_cuda.h"
#include "cuda/wdt_cuda.h"
#endif

namespace at {

namespace {

std::string voxelText(const Dims& d, std::size_t index) {
  const std::size_t i = index % std::size_t(d.x), j = (index / std::size_t(d.x)) % std::size_t(d.y),
                    k = index / (std::size_t(d.x) * std::size_t(d.y));
  return "voxel (" + std::to_string(i) + "," + std::to_string(j) + "," + std::to_string(k) + ")";
}

// The seeds sorted by voxel, duplicates of the same label merged. Errors name the seed.
Result<std::vector<GrowthSeed>> checkedSeeds(const Dims& d, std::vector<GrowthSeed> seeds) {
  if (seeds.empty()) return fail("grow from seeds: no seed given");
  for (const GrowthSeed& s : seeds)
    if (s.index >= d.count())
      return fail("grow from seeds: seed index " + std::to_string(s.index) + " lies outside the " + d.toString() +
                  " grid");
  std::sort(seeds.begin(), seeds.end(), [](const GrowthSeed& a, const GrowthSeed& b) {
    return a.index != b.index ? a.index < b.index : a.label < b.label;
  });
  seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
  for (std::size_t i = 0; i < seeds.size(); ++i) {
    if (seeds[i].label == 0xFFFF)
      return fail("grow from seeds: label 65535 is reserved (labels are 0 … 65534)");
    if (i > 0 && seeds[i].index == seeds[i - 1].index)
      return fail("grow from seeds: " + voxelText(d, seeds[i].index) + " is seeded with two labels, " +
                  std::to_string(seeds[i - 1].label) + " and " + std::to_string(seeds[i].label));
  }
  return seeds;
}

// Fixed-point units per unit of cost: as many as keep every distance below 2^30 (kGrowthInf is
// 2^31 − 1). No distance exceeds the cost of a staircase path along the axes from the nearest seed:
// at most (largest weight) × (nx·sx + ny·sy + nz·sz) before rounding, and rounding each of its
// nx + ny + nz steps adds at most one unit. 512³ voxels of 1 mm with gradient costs (at most
// base + 1 per mm on that grid) get ~6.6·10⁵ units per unit of cost, a resolution far below any
// step's cost.
float fixedPointScale(const Geometry& g, wdt::CostKernel kernel, float base) {
  float lo = 0, hi = 0;
  const float shortest = float(std::min({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]}));
  wdt::weightRange(kernel, base, shortest, lo, hi);
  const double extentMm = g.dims.x * g.spacingMm[0] + g.dims.y * g.spacingMm[1] + g.dims.z * g.spacingMm[2];
  const double steps = double(g.dims.x) + g.dims.y + g.dims.z;
  const double budget = double(1 << 30) - 2 * steps;
  return float(budget / (double(hi) * extentMm * 1.01));
}

// The growth's problem; `density`, where given, holds the density bytes already computed for this
// volume under the same window, smoothing and edge sigma (they are copied, not computed again).
Result<GrowthProblem> makeProblem(const Volume& volume, const GrowthParams& params,
                                  const std::vector<std::uint8_t>* density = nullptr) {
  if (auto ok = validateGrowthParams(params); !ok) return tl::unexpected(ok.error());
  const Dims d = volume.dims();
  if (d.count() == 0 || volume.voxels.size() != d.count())
    return fail("grow from seeds: the volume is empty (" + d.toString() + ")");
  if (d.count() >= (std::size_t(1) << 32))
    return fail("grow from seeds: the grid " + d.toString() + " has more than 2^32 voxels");
  WdtParams window;
  window.huMin = params.windowMin;
  window.huMax = params.windowMax;
  const std::vector<std::uint8_t> lut = densityTable(window);
  GrowthProblem problem;
  problem.grid = volume.geometry;
  problem.density.resize(d.count());
  if (density && density->size() == d.count()) {
    problem.density = *density;
  } else if (params.smoothingVoxels > 0) {
    const std::vector<float> values = params.edgeSigma > 0
                                          ? wdt::edgePreservingSmoothed(volume, params.smoothingVoxels, params.edgeSigma)
                                          : wdt::gaussianSmoothed(volume, params.smoothingVoxels);
    for (std::size_t i = 0; i < d.count(); ++i)
      problem.density[i] = wdt::densityByte(values[i], params.windowMin, params.windowMax);
  } else {
    for (std::size_t i = 0; i < d.count(); ++i) problem.density[i] = lut[std::size_t(volume.voxels[i] + 32768)];
  }
  if (params.limitRange) {
    problem.blocked.resize(d.count());
    for (std::size_t i = 0; i < d.count(); ++i)
      problem.blocked[i] = volume.voxels[i] < params.rangeMin || volume.voxels[i] > params.rangeMax;
  }
  problem.kernel = wdt::costKernel(params.rule, params.weight);
  problem.baseCost = params.baseCost;
  problem.scale = fixedPointScale(problem.grid, problem.kernel, params.baseCost);
  return problem;
}

}  // namespace

Status validateGrowthParams(const GrowthParams& p) {
  if (!std::isfinite(p.windowMin) || !std::isfinite(p.windowMax) || !(p.windowMax > p.windowMin))
    return fail("growth params: the window must have max > min, got " + std::to_string(p.windowMin) + ".." +
                std::to_string(p.windowMax));
  if (!std::isfinite(p.smoothingVoxels) || p.smoothingVoxels < 0 || p.smoothingVoxels > 8)
    return fail("growth params: smoothingVoxels must be 0 … 8, got " + std::to_string(p.smoothingVoxels));
  if (p.limitRange && (!std::isfinite(p.rangeMin) || !std::isfinite(p.rangeMax) || !(p.rangeMax >= p.rangeMin)))
    return fail("growth params: the range limit must have max >= min, got " + std::to_string(p.rangeMin) + ".." +
                std::to_string(p.rangeMax));
  if (p.limitRange && p.backend == WdtBackend::Cuda)
    return fail("growth params: a range limit grows on the CPU only, backend cuda cannot honour it");
  if (!std::isfinite(p.edgeSigma) || p.edgeSigma < 0)
    return fail("growth params: edgeSigma must be >= 0 (0: plain Gaussian smoothing), got " + std::to_string(p.edgeSigma));
  if (!std::isfinite(p.baseCost) || !(p.baseCost > 0))
    return fail("growth params: baseCost must be > 0 (a step that costs nothing lets labels cross freely), got " +
                std::to_string(p.baseCost));
  return {};
}

struct LabelGrowth::State {
  GrowthParams params;
  Geometry grid;
  std::unique_ptr<GrowthEngine> engine;
  LabelMap labels;
  std::vector<GrowthSeed> seeds;  // of the last update, sorted by voxel
  bool started = false;
  bool converged = false;         // the last update reached the fixed point (not cancelled)
  std::string warning;            // why auto fell back to the CPU; reported by the first update
  const std::int16_t* volumeData = nullptr;  // the voxels it was created on (create's sameValues check)
};

LabelGrowth::LabelGrowth(std::unique_ptr<State> state) : state_(std::move(state)) {}
LabelGrowth::~LabelGrowth() = default;
LabelGrowth::LabelGrowth(LabelGrowth&&) noexcept = default;
LabelGrowth& LabelGrowth::operator=(LabelGrowth&&) noexcept = default;

Result<LabelGrowth> LabelGrowth::create(const Volume& volume, const GrowthParams& params) {
  return create(volume, params, nullptr);
}

Result<LabelGrowth> LabelGrowth::create(const Volume& volume, const GrowthParams& params, const LabelGrowth* sameValues) {
  const std::vector<std::uint8_t>* density = nullptr;
  if (sameValues && sameValues->state_) {
    const State& o = *sameValues->state_;
    const bool sameValuesAsThese = o.volumeData == volume.voxels.data() && o.grid.dims == volume.dims() &&
                                   o.params.windowMin == params.windowMin && o.params.windowMax == params.windowMax &&
                                   o.params.smoothingVoxels == params.smoothingVoxels && o.params.edgeSigma == params.edgeSigma;
    if (sameValuesAsThese) density = o.engine->hostDensity();
  }
  auto problem = makeProblem(volume, params, density);
  if (!problem) return tl::unexpected(problem.error());
  auto state = std::make_unique<State>();
  state->volumeData = volume.voxels.data();
  state->params = params;
  state->grid = volume.geometry;
  state->labels = LabelMap(volume.geometry, 0);
#if defined(AT_HAVE_CUDA)
  const bool available = cuda::queryDevice().available;
  if (params.backend == WdtBackend::Cuda && !available)
    return fail("grow from seeds: backend cuda requested but " + cuda::queryDevice().reason);
  if (params.limitRange && params.backend == WdtBackend::Auto && available)
    state->warning = "a range limit grows on the CPU (the CUDA engine has none)";
  else if (params.backend == WdtBackend::Cuda || (params.backend == WdtBackend::Auto && available)) {
    auto engine = cuda::makeCudaGrowthEngine(*problem);
    if (engine) {
      state->engine = std::move(*engine);
    } else if (params.backend == WdtBackend::Cuda) {
      return tl::unexpected(engine.error());
    } else {
      state->warning = "CUDA growth failed to start, growing on the CPU instead: " + engine.error().message;
    }
  }
#else
  if (params.backend == WdtBackend::Cuda) return fail("grow from seeds: this build has no CUDA backend");
#endif
  if (!state->engine) state->engine = makeCpuGrowthEngine(std::move(*problem));
  return LabelGrowth(std::move(state));
}

Result<GrowthStats> LabelGrowth::update(const std::vector<GrowthSeed>& seedsIn, const WdtControl& control) {
  const auto t0 = std::chrono::steady_clock::now();
  State& s = *state_;
  auto seeds = checkedSeeds(s.grid.dims, seedsIn);
  if (!seeds) return tl::unexpected(seeds.error());

  GrowthChange change;
  GrowthStats stats;
  stats.incremental = s.started;
  if (!s.started) {
    change.fromScratch = true;
    change.writeSeeds = *seeds;
    stats.seedsAdded = seeds->size();
  } else {
    // Merge walk over both sorted lists: a voxel seeded before and not now (or with another label
    // now) resets its old label; a voxel seeded now and not before (or relabelled) is written.
    std::set<std::uint16_t> reset;
    std::vector<GrowthSeed> removed;
    std::vector<char> written(seeds->size(), 0);
    const std::vector<GrowthSeed>& before = s.seeds;
    std::size_t i = 0, j = 0;
    while (i < before.size() || j < seeds->size()) {
      const bool takeOld = j == seeds->size() || (i < before.size() && before[i].index < (*seeds)[j].index);
      const bool takeNew = i == before.size() || (j < seeds->size() && (*seeds)[j].index < before[i].index);
      if (takeOld) {
        removed.push_back(before[i]);
        reset.insert(before[i++].label);
        ++stats.seedsRemoved;
      } else if (takeNew) {
        written[j++] = 1;
        ++stats.seedsAdded;
      } else {
        if (before[i].label != (*seeds)[j].label) {
          removed.push_back(before[i]);
          reset.insert(before[i].label);
          written[j] = 1;
          ++stats.seedsRemoved;
          ++stats.seedsAdded;
        }
        ++i, ++j;
      }
    }
    if (s.engine->resetsGrownFromRemovedSeeds() && s.converged) {
      // Only what grew from the removed seeds is reset: the kept seeds keep their pairs. (That
      // needs the fixed point, where every voxel's pair comes from a neighbour's: after a cancelled
      // update the labels' voxels are reset.)
      change.removedSeeds = std::move(removed);
      for (std::size_t k = 0; k < seeds->size(); ++k)
        if (written[k]) change.writeSeeds.push_back((*seeds)[k]);
    } else {
      change.resetLabels.assign(reset.begin(), reset.end());
      // The reset takes every voxel of those labels, seeds included: the kept ones are written again.
      for (std::size_t k = 0; k < seeds->size(); ++k)
        if (written[k] || reset.count((*seeds)[k].label)) change.writeSeeds.push_back((*seeds)[k]);
    }
  }
  if (auto ok = s.engine->apply(change, control, stats); !ok) return tl::unexpected(ok.error());
  s.seeds = std::move(*seeds);
  s.started = true;
  s.converged = stats.converged;
  if (auto ok = s.engine->readLabels(s.labels); !ok) return tl::unexpected(ok.error());
  if (!s.warning.empty()) stats.warning = std::exchange(s.warning, std::string());
  stats.msTotal = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

const Geometry& LabelGrowth::grid() const { return state_->grid; }
const GrowthParams& LabelGrowth::params() const { return state_->params; }
const LabelMap& LabelGrowth::labels() const { return state_->labels; }

Result<FloatVolume> LabelGrowth::distances() const {
  FloatVolume out;
  if (auto ok = state_->engine->readDistances(out); !ok) return tl::unexpected(ok.error());
  return out;
}

Result<GrowthResult> exactLabelGrowth(const Volume& volume, const std::vector<GrowthSeed>& seeds,
                                      const GrowthParams& params) {
  auto problem = makeProblem(volume, params);
  if (!problem) return tl::unexpected(problem.error());
  auto checked = checkedSeeds(volume.dims(), seeds);
  if (!checked) return tl::unexpected(checked.error());
  return exactGrowthOnProblem(*problem, *checked);
}

}  // namespace at
