// The persistent sweep kernel (at::cuda::setPersistentSweeps): one cooperative launch a sweep
// whose tiles wait on their neighbours' progress counters instead of a launch a plane group. It
// must keep every contract of the group launches: fixed passes equal the CPU backend bit for bit,
// converged fields equal the exact reference bit for bit, runs are deterministic. A wrong wait
// would read a neighbour's plane before it is written (a wrong field) or never return (a hang:
// the GPU runs of these tests are wrapped in a timeout). Skipped without a GPU.
#include <doctest/doctest.h>

#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "cuda/wdt_cuda.h"
#include "test_support.h"
#include "wdt/problem.h"
#include "wdt_cuda_cases.h"

using namespace wdt_cuda_cases;

namespace {

// Turns the persistent sweeps on for every tile for one scope, and the default back after.
struct PersistentSweeps {
  PersistentSweeps() { at::cuda::setPersistentSweeps(true); }
  ~PersistentSweeps() {
    at::cuda::setPersistentSweeps(at::cuda::PersistentSweeps::Auto);
    at::cuda::setConvergeSweepsBeforeBricks(-1);
  }
};

}  // namespace

TEST_CASE("persistent sweeps: fixed passes equal the CPU's bit for bit on one-wave, large and thin grids") {
  if (!requireDevice()) return;
  PersistentSweeps on;
  std::mt19937_64 rng(at::test::freshSeed("cuda persistent passes"));

  // A grid whose tiles fit any GPU at once runs all six sweeps of its pass persistently (the pass
  // is captured once for a problem's parameters, then replayed for the second pass).
  {
    const long long before = at::cuda::persistentSweepsCaptured();
    checkFixedPassesMatchCpu(randomProblem(rng, {64, 64, 64}, {0.8, 0.6, 1.5}, StepRule::Entering, WeightRule::Density));
    CHECK(at::cuda::persistentSweepsCaptured() - before == 6);
  }

  // Edge sizes (partial tiles and plane groups, one voxel thin along each axis), several tiles and
  // groups, and planes of more default tiles than an H200 has multiprocessors: 520 × 300 runs
  // the large tile persistently (90 blocks), 1100 × 300 needs two waves of it and falls back to
  // group launches. Every rule and weight on the small grids.
  std::vector<at::Dims> sizes(std::begin(kEdgeSizes), std::end(kEdgeSizes));
  for (const at::Dims d : {at::Dims{97, 45, 38}, at::Dims{1, 1, 300}, at::Dims{300, 1, 1}, at::Dims{3, 257, 2},
                           at::Dims{129, 2, 17}, at::Dims{180, 170, 19}})
    sizes.push_back(d);
  const long long before = at::cuda::persistentSweepsCaptured();
  for (const at::Dims& dims : sizes) {
    for (StepRule rule : kRules) {
      for (WeightRule weight : kWeights) {
        checkFixedPassesMatchCpu(randomProblem(rng, dims, {0.7, 0.9, 1.6}, rule, weight));
      }
    }
  }
  for (const at::Dims& dims : {at::Dims{520, 300, 9}, at::Dims{1100, 300, 13}}) {
    for (StepRule rule : kRules) {
      checkFixedPassesMatchCpu(randomProblem(rng, dims, {0.7, 0.9, 1.6}, rule, WeightRule::Gradient));
    }
  }
  const long long captured = at::cuda::persistentSweepsCaptured() - before;
  std::printf("persistent sweeps: %lld sweeps captured as persistent launches\n", captured);
  CHECK(captured >= 6 * long(sizes.size()));
}

TEST_CASE("persistent sweeps: converged fields equal the exact reference bit for bit, and runs are deterministic") {
  if (!requireDevice()) return;
  PersistentSweeps on;
  std::mt19937_64 rng(at::test::freshSeed("cuda persistent converge"));
  std::vector<WdtProblem> problems;
  problems.push_back(randomProblem(rng, {97, 45, 38}, {0.7, 1.3, 2.5}, StepRule::Entering, WeightRule::Density));
  problems.push_back(randomProblem(rng, {33, 17, 65}, {1, 1, 1}, StepRule::Trapezoid, WeightRule::Gradient));
  problems.push_back(randomProblem(rng, {136, 136, 120}, {0.8f, 0.8f, 1.1f}, StepRule::Entering, WeightRule::Density));
  for (WdtProblem& p : problems) {
    p.params.converge = true;
    p.params.maxPasses = 400;
    CAPTURE(p.grid.dims.toString());
    auto exact = at::exactWdtOnProblem(p);
    REQUIRE(exact.has_value());
    // Whole-volume passes only (persistent sweeps to the fixed point), and 2 passes then rounds.
    for (const int passesFirst : {1000, 2}) {
      CAPTURE(passesFirst);
      at::cuda::setConvergeSweepsBeforeBricks(passesFirst);
      at::WdtStats stats;
      const auto gpu = gpuField(p, &stats);
      CHECK(stats.converged);
      CHECK(stats.passesRun >= 1);
      if (passesFirst == 1000) CHECK(stats.scheme == "sweeps");
      CHECK_MESSAGE(sameBits(gpu, exact->voxels), describeDifference(gpu, exact->voxels, p.grid.dims));
      for (int run = 0; run < 2; ++run) CHECK(sameBits(gpuField(p), gpu));
    }
  }
}

TEST_CASE("persistent sweeps by default: only where the large tile runs, with the CPU's fields bit for bit") {
  if (!requireDevice()) return;
  at::cuda::setPersistentSweeps(at::cuda::PersistentSweeps::Auto);
  std::mt19937_64 rng(at::test::freshSeed("cuda persistent default"));
  // 64³: 8 default tiles a plane, one wave on any GPU: group launches (unless the environment's
  // AT_WDT_CUDA_PERSISTENT overrides the default, as in the test runs that set it).
  const bool overridden = std::getenv("AT_WDT_CUDA_PERSISTENT") != nullptr;
  long long before = at::cuda::persistentSweepsCaptured();
  checkFixedPassesMatchCpu(randomProblem(rng, {64, 64, 64}, {0.8, 0.6, 1.5}, StepRule::Entering, WeightRule::Density));
  if (!overridden) CHECK(at::cuda::persistentSweepsCaptured() - before == 0);
  // 520 × 300 planes: 323 default tiles, the large tile (90 blocks) on a GPU of fewer
  // multiprocessors (e.g. an H200's 132), then persistently.
  before = at::cuda::persistentSweepsCaptured();
  for (StepRule rule : kRules) {
    checkFixedPassesMatchCpu(randomProblem(rng, {520, 300, 9}, {0.7, 0.9, 1.6}, rule, WeightRule::Gradient));
  }
  std::printf("persistent sweeps by default: %lld sweeps captured as persistent launches at 520 x 300 x 9\n",
              at::cuda::persistentSweepsCaptured() - before);
}
