// CUDA backend vs the CPU backend and the exact reference. Every test needing a GPU prints
// "SKIPPED: no CUDA device (<reason>)" and passes where there is none (CI, the dev machines).
//
// The GPU field must equal the CPU backend's bit for bit after any number of passes (same stencil,
// same plane order, same float operations), hence also in converge mode, where both equal the
// exact reference; deterministically (two runs bitwise identical).
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "cuda/wdt_cuda.h"
#include "test_support.h"
#include "wdt/problem.h"

#include "wdt_cuda_cases.h"

using namespace wdt_cuda_cases;

TEST_CASE("queryDevice answers without a GPU instead of crashing, and the backend then returns an error") {
  const auto& info = at::cuda::queryDevice();
  CHECK(&info == &at::cuda::queryDevice());  // cached
  if (info.available) {
    CHECK_FALSE(info.name.empty());
    return;
  }
  CHECK_FALSE(info.reason.empty());
  WdtProblem p;
  p.grid.dims = {2, 2, 2};
  p.density.assign(8, 0);
  p.seeds.assign(8, 0);
  p.seeds[0] = 1;
  auto r = at::cuda::runCudaBackend(p, {});
  REQUIRE_FALSE(r.has_value());
  CHECK(r.error().message.find(info.reason) != std::string::npos);
  at::test::skipf("no CUDA device (%s)", info.reason.c_str());
}

TEST_CASE("converged GPU fields equal the CPU backend and the exact reference for every rule, weight and edge size") {
  if (!requireDevice()) return;
  std::mt19937_64 rng(at::test::freshSeed("cuda converge"));
  for (const at::Dims& dims : kEdgeSizes) {
    for (StepRule rule : kRules) {
      for (WeightRule weight : kWeights) {
        const at::Vec3 spacing = (dims.x % 2) ? at::Vec3{0.7, 1.3, 2.5} : at::Vec3{1, 1, 1};
        WdtProblem p = randomProblem(rng, dims, spacing, rule, weight);
        p.params.converge = true;
        p.params.maxPasses = 200;
        CAPTURE(dims.toString());
        const std::string ruleName = at::toString(rule);
        CAPTURE(ruleName);
        const std::string weightName = at::toString(weight);
        CAPTURE(weightName);
        at::WdtStats stats;
        const auto gpu = gpuField(p, &stats);
        const auto cpu = cpuField(p);
        auto exact = at::exactWdtOnProblem(p);
        REQUIRE(exact.has_value());
        CHECK(stats.converged);
        CHECK(maxRelDiff(gpu, cpu) <= 1e-6);
        CHECK(maxRelDiff(gpu, exact->voxels) <= 1e-6);
        for (std::size_t i = 0; i < gpu.size(); ++i) {
          if (p.seeds[i]) REQUIRE(gpu[i] == 0.0f);
        }
      }
    }
  }
}

// A serpentine maze: dense walls across y every 4 rows, each open at alternating ends in x, so the
// path from the seed corner doubles back nz·(ny / 4) times (many brick rounds, bricks re-queued).
WdtProblem serpentine(at::Dims dims, StepRule rule, WeightRule weight) {
  WdtProblem p;
  p.grid.dims = dims;
  p.grid.spacingMm = {0.8, 1.1, 1.7};
  p.density.assign(dims.count(), 0);
  p.seeds.assign(dims.count(), 0);
  for (int k = 0; k < dims.z; ++k)
    for (int j = 3; j < dims.y; j += 4)
      for (int i = 0; i < dims.x; ++i) {
        const bool gapRight = (j / 4) % 2 == 0;
        if (gapRight ? i < dims.x - 2 : i >= 2) p.density[dims.index(i, j, k)] = 255;
      }
  p.seeds[dims.index(0, 0, 0)] = 1;
  p.params.rule = rule;
  p.params.weight = weight;
  p.params.baseCost = 0.001f;  // air costs 1/1000 of a wall: going round is cheaper than through
  return p;
}

TEST_CASE("converge mode runs brick rounds that equal the CPU and the exact reference on mazes and larger volumes, deterministically") {
  if (!requireDevice()) return;
  std::mt19937_64 rng(at::test::freshSeed("cuda brick rounds"));
  std::vector<WdtProblem> problems;
  problems.push_back(serpentine({45, 70, 11}, StepRule::Entering, WeightRule::Density));
  problems.push_back(serpentine({64, 64, 9}, StepRule::Trapezoid, WeightRule::Density));
  problems.push_back(randomProblem(rng, {97, 45, 38}, {0.7, 1.3, 2.5}, StepRule::Entering, WeightRule::Density));
  problems.push_back(randomProblem(rng, {64, 64, 64}, {1, 1, 1}, StepRule::Entering, WeightRule::Gradient));
  problems.push_back(randomProblem(rng, {24, 130, 17}, {1, 1, 1}, StepRule::Trapezoid, WeightRule::Density));
  for (WdtProblem& p : problems) {
    p.params.converge = true;
    p.params.maxPasses = 64;
    CAPTURE(p.grid.dims.toString());
    const auto cpu = cpuField(p);
    auto exact = at::exactWdtOnProblem(p);
    REQUIRE(exact.has_value());
    for (int sweepsFirst : {0, 2}) {  // rounds from the seeds, and after two whole-volume passes
      CAPTURE(sweepsFirst);
      at::cuda::setConvergeSweepsBeforeBricks(sweepsFirst);
      at::WdtStats stats;
      const auto gpu = gpuField(p, &stats);
      CHECK(stats.converged);
      CHECK(stats.msCompute > 0);
      if (sweepsFirst == 0) {
        CHECK(stats.scheme == "bricks");
        CHECK(stats.passesRun == 0);
        CHECK(stats.rounds > 0);
      } else {
        CHECK(stats.passesRun >= 1);
        CHECK(stats.passesRun <= sweepsFirst);
        // Converged within the passes ("sweeps", no rounds), or finished by rounds (perhaps zero
        // rounds, when the start kernel finds every voxel settled).
        CHECK((stats.scheme == "sweeps+bricks" || (stats.scheme == "sweeps" && stats.rounds == 0)));
      }
      CHECK_MESSAGE(sameBits(gpu, cpu), describeDifference(gpu, cpu, p.grid.dims));
      CHECK(maxRelDiff(gpu, exact->voxels) <= 1e-6);
      for (int run = 0; run < 2; ++run) {
        at::WdtStats again;
        CHECK(sameBits(gpuField(p, &again), gpu));
        CHECK(again.rounds == stats.rounds);
      }
      std::printf("brick rounds: %s, %d passes + %d rounds, %.3f ms\n", p.grid.dims.toString().c_str(), stats.passesRun,
                  stats.rounds, stats.msCompute);
    }
  }
  at::cuda::setConvergeSweepsBeforeBricks(-1);  // the default again
  // The maze needs more rounds than the walls allow with a pass cap of 1: not converged, and the
  // partial field is never below the exact distances.
  WdtProblem capped = serpentine({45, 70, 11}, StepRule::Entering, WeightRule::Density);
  capped.params.converge = true;
  capped.params.maxPasses = 1;
  at::WdtStats stats;
  const auto partial = gpuField(capped, &stats);
  CHECK_FALSE(stats.converged);
  // A grid this small starts the rounds from the seeds; they stop after maxPasses × 2 × (bricks of
  // 16 voxels along the longest axis) rounds.
  CHECK(stats.scheme == "bricks");
  CHECK(stats.passesRun == 0);
  CHECK(stats.rounds == 1 * 2 * ((70 + 15) / 16));
  auto exact = at::exactWdtOnProblem(capped);
  REQUIRE(exact.has_value());
  CHECK(countBelow(partial, exact->voxels, 1e-6) == 0);
  CHECK(maxRelDiff(partial, exact->voxels) > 0);

  // Above 128³ voxels the default runs 2 whole-volume passes, and a third when the second still
  // lowered many values, before the rounds; the field is the same fixed point.
  for (WdtProblem p : {serpentine({136, 136, 120}, StepRule::Entering, WeightRule::Density),
                       randomProblem(rng, {136, 136, 120}, {0.8f, 0.8f, 1.1f}, StepRule::Entering,
                                     WeightRule::Density)}) {
    p.params.converge = true;
    p.params.maxPasses = 64;
    CAPTURE(p.grid.dims.toString());
    std::vector<std::pair<int, int>> progress;
    at::WdtControl control;
    control.progress = [&](int done, int planned) { progress.emplace_back(done, planned); };
    auto r = at::cuda::runCudaBackend(p, control);
    REQUIRE_MESSAGE(r.has_value(), (r ? std::string() : r.error().message));
    const at::WdtStats& large = r->stats;
    const std::vector<float>& gpu = r->field.distances.voxels;
    CHECK(large.converged);
    CHECK(large.passesRun >= 2);
    CHECK(large.passesRun <= 3);
    REQUIRE(progress.size() == std::size_t(large.passesRun));
    CHECK(progress.back() == std::make_pair(large.passesRun, large.passesRun));
    CHECK_MESSAGE(sameBits(gpu, cpuField(p)), "large grid, default passes before the rounds");
    std::printf("default passes before the rounds: %s, %d passes + %d rounds, %.3f ms\n",
                p.grid.dims.toString().c_str(), large.passesRun, large.rounds, large.msCompute);
  }

  // Fixed passes stay whole-volume sweeps.
  capped.params.converge = false;
  capped.params.passes = 1;
  gpuField(capped, &stats);
  CHECK(stats.scheme == "sweeps");
  CHECK(stats.passesRun == 1);
}

TEST_CASE("fixed-pass GPU fields equal the CPU backend's bit for bit for every rule, weight and size") {
  if (!requireDevice()) return;
  std::mt19937_64 rng(at::test::freshSeed("cuda exact passes"));
  std::vector<at::Dims> sizes(std::begin(kEdgeSizes), std::end(kEdgeSizes));
  sizes.push_back({64, 64, 64});
  sizes.push_back({97, 45, 38});
  for (const at::Dims& dims : sizes) {
    for (StepRule rule : kRules) {
      for (WeightRule weight : kWeights) {
        checkFixedPassesMatchCpu(randomProblem(rng, dims, {0.8, 0.6, 1.5}, rule, weight));
      }
    }
  }
}

TEST_CASE("fixed-pass GPU fields equal the CPU's bit for bit over many tiles and plane groups") {
  if (!requireDevice()) return;
  std::mt19937_64 rng(at::test::freshSeed("cuda tiles"));
  // Planes of several 32×16-lane tiles with partial last tiles and plane groups (8 planes), a
  // plane of exactly one tile and group, and planes with many tiles in both directions. Planes
  // of more 32×16 tiles than the GPU has multiprocessors run with 64×32 tiles: on an H200 (132)
  // the 520 × 300 planes in one wave (90 tiles, partial in both directions) and the 1100 × 300
  // ones in two (180), with partial plane groups (6 planes) at 9 and 13 planes.
  const at::Dims sizes[] = {{97, 45, 38}, {33, 17, 65},   {180, 170, 19},  {32, 16, 8},
                            {16, 32, 16}, {520, 300, 9}, {1100, 300, 13}};
  for (const at::Dims& dims : sizes) {
    for (StepRule rule : kRules) {
      for (WeightRule weight : kWeights) {
        const bool large = dims.x == 180 || dims.x == 1100;
        if (large && !(weight == WeightRule::Density || weight == WeightRule::Gradient)) continue;
        checkFixedPassesMatchCpu(randomProblem(rng, dims, {0.7, 0.9, 1.6}, rule, weight));
      }
    }
  }
}

// Single lanes and one-voxel-thin slabs along every axis, and sizes one past the multiples of the
// sweep tile (32 × 16 lanes), the plane group (8 planes) and the brick (16³): every pass equals the
// CPU's bit for bit, and converged fields (passes, then brick rounds) equal the exact reference.
TEST_CASE("thin volumes and sizes off the tile, group and brick multiples equal the CPU and the exact reference") {
  if (!requireDevice()) return;
  std::mt19937_64 rng(at::test::freshSeed("cuda thin and odd sizes"));
  const at::Dims sizes[] = {{1, 1, 300}, {300, 1, 1}, {1, 300, 1}, {17, 1, 70}, {1, 65, 33},
                            {49, 17, 9}, {129, 2, 17}, {3, 257, 2}, {33, 33, 1}};
  for (const at::Dims& dims : sizes) {
    for (StepRule rule : kRules) {
      for (WeightRule weight : kWeights) {
        WdtProblem p = randomProblem(rng, dims, {0.9, 0.7, 1.3}, rule, weight);
        checkFixedPassesMatchCpu(p);
        p.params.converge = true;
        p.params.maxPasses = 400;
        for (const int passesFirst : {0, 2}) {
          at::cuda::setConvergeSweepsBeforeBricks(passesFirst);
          at::WdtStats stats;
          const auto gpu = gpuField(p, &stats);
          auto exact = at::exactWdtOnProblem(p);
          REQUIRE(exact.has_value());
          CAPTURE(dims.toString());
          CAPTURE(passesFirst);
          CHECK(stats.converged);
          CHECK_MESSAGE(sameBits(gpu, exact->voxels), describeDifference(gpu, exact->voxels, dims));
        }
        at::cuda::setConvergeSweepsBeforeBricks(-1);
      }
    }
  }
}

TEST_CASE("two GPU runs give bitwise identical fields") {
  if (!requireDevice()) return;
  std::mt19937_64 rng(at::test::freshSeed("cuda determinism"));
  for (int passes : {1, 2}) {
    WdtProblem p = randomProblem(rng, {131, 77, 59}, {0.9, 0.9, 2.0}, StepRule::Trapezoid, WeightRule::Density);
    p.params.passes = passes;
    const auto first = gpuField(p);
    for (int run = 0; run < 3; ++run) CHECK(sameBits(gpuField(p), first));
  }
}

TEST_CASE("the GPU reports per-pass progress and timings, and stops when cancelled") {
  if (!requireDevice()) return;
  std::mt19937_64 rng(at::test::freshSeed("cuda control"));
  WdtProblem p = randomProblem(rng, {48, 40, 36}, {1, 1, 1}, StepRule::Entering, WeightRule::Density);
  p.params.passes = 3;
  std::vector<std::pair<int, int>> calls;
  at::WdtControl control;
  control.progress = [&](int done, int planned) { calls.emplace_back(done, planned); };
  auto r = at::cuda::runCudaBackend(p, control);
  REQUIRE(r.has_value());
  REQUIRE(calls.size() == 3);
  CHECK(calls[2] == std::pair<int, int>{3, 3});
  CHECK(r->stats.passesRun == 3);
  CHECK(r->stats.msPerPass.size() == 3);
  CHECK((r->stats.backendUsed == at::WdtBackend::Cuda));
  CHECK(r->stats.device == at::cuda::queryDevice().name);
  CHECK(r->field.distances.geometry.dims == p.grid.dims);

  std::atomic<bool> cancel{true};
  at::WdtControl cancelled;
  cancelled.cancel = &cancel;
  auto c = at::cuda::runCudaBackend(p, cancelled);
  REQUIRE(c.has_value());
  CHECK(c->stats.cancelled);
  CHECK(c->stats.passesRun == 0);
  CHECK_FALSE(c->stats.converged);
  auto exact = at::exactWdtOnProblem(p);
  REQUIRE(exact.has_value());
  CHECK(countBelow(c->field.distances.voxels, exact->voxels, 1e-6) == 0);

  // Cancel after the first pass: the partial field is returned, one pass recorded.
  std::atomic<bool> later{false};
  at::WdtControl afterOne;
  afterOne.cancel = &later;
  afterOne.progress = [&](int, int) { later = true; };
  auto d = at::cuda::runCudaBackend(p, afterOne);
  REQUIRE(d.has_value());
  CHECK(d->stats.cancelled);
  CHECK(d->stats.passesRun == 1);
}

TEST_CASE("a field kept on the device copies back to the same values as runCudaBackend") {
  if (!requireDevice()) return;
  std::mt19937_64 rng(at::test::freshSeed("cuda device field"));
  WdtProblem p = randomProblem(rng, {50, 33, 20}, {1, 1, 1}, StepRule::Trapezoid, WeightRule::Density);
  at::WdtStats stats;
  auto field = at::cuda::runCudaBackendOnDevice(p, {}, &stats);
  REQUIRE(field.has_value());
  CHECK(field->devicePointer() != nullptr);
  CHECK(field->grid().dims == p.grid.dims);
  CHECK(stats.passesRun == p.params.passes);
  at::FloatVolume host;
  REQUIRE(at::cuda::copyToHost(*field, host).has_value());
  const auto direct = gpuField(p);
  CHECK(std::memcmp(host.voxels.data(), direct.data(), direct.size() * sizeof(float)) == 0);

  at::cuda::DeviceField moved = std::move(*field);
  CHECK(moved.devicePointer() != nullptr);
  auto filled = at::cuda::makeDeviceField(p.grid, 7.5f);
  REQUIRE(filled.has_value());
  REQUIRE(at::cuda::copyToHost(*filled, host).has_value());
  CHECK(std::all_of(host.voxels.begin(), host.voxels.end(), [](float v) { return v == 7.5f; }));
}

TEST_CASE("an impossible allocation comes back as an error naming the CUDA call, and the device stays usable") {
  if (!requireDevice()) return;
  at::Geometry huge;
  huge.dims = {100000, 100000, 100000};  // 4·10^15 bytes
  auto r = at::cuda::makeDeviceField(huge, 0.0f);
  REQUIRE_FALSE(r.has_value());
  CHECK(r.error().message.find("cudaMalloc") != std::string::npos);
  std::printf("expected error: %s\n", r.error().message.c_str());

  std::mt19937_64 rng(at::test::freshSeed("cuda after error"));
  WdtProblem p = randomProblem(rng, {20, 20, 20}, {1, 1, 1}, StepRule::Entering, WeightRule::Uniform);
  p.params.converge = true;
  const auto gpu = gpuField(p);
  CHECK(maxRelDiff(gpu, cpuField(p)) <= 1e-6);
}

TEST_CASE("a resident device volume gives the host path's fields bit for bit, downsampled too, and names a missing label") {
  std::mt19937_64 rng(at::test::freshSeed("cuda device volume"));
  // A random CT (HU over the whole window and beyond) with three labelled blobs.
  const at::Dims dims{37, 29, 23};
  at::Volume ct;
  ct.geometry.dims = dims;
  ct.geometry.spacingMm = {0.7, 0.9, 1.3};
  ct.voxels.resize(dims.count());
  at::LabelMap labels;
  labels.geometry = ct.geometry;
  labels.voxels.assign(dims.count(), 0);
  std::uniform_int_distribution<int> hu(-1400, 3200);
  for (auto& v : ct.voxels) v = std::int16_t(hu(rng));
  std::uniform_int_distribution<int> at(0, 1 << 20);
  for (std::uint16_t label = 1; label <= 3; ++label) {
    const int ci = at(rng) % dims.x, cj = at(rng) % dims.y, ck = at(rng) % dims.z;
    for (int k = std::max(0, ck - 2); k < std::min(dims.z, ck + 2); ++k)
      for (int j = std::max(0, cj - 2); j < std::min(dims.y, cj + 2); ++j)
        for (int i = std::max(0, ci - 3); i < std::min(dims.x, ci + 3); ++i) labels.voxels[dims.index(i, j, k)] = label;
  }
  auto uploaded = at::cuda::uploadVolume(ct, labels);
  if (!at::cuda::queryDevice().available) {
    REQUIRE_FALSE(uploaded.has_value());
    at::test::skipf("no CUDA device (%s)", uploaded.error().message.c_str());
    return;
  }
  REQUIRE_MESSAGE(uploaded.has_value(), (uploaded ? std::string() : uploaded.error().message));
  for (const int factor : {1, 2, 3}) {
    for (std::uint16_t label = 1; label <= 3; ++label) {
      at::Mask mask;
      mask.geometry = ct.geometry;
      mask.voxels.resize(dims.count());
      for (std::size_t i = 0; i < dims.count(); ++i) mask.voxels[i] = labels.voxels[i] == label;
      if (std::none_of(mask.voxels.begin(), mask.voxels.end(), [](std::uint8_t v) { return v != 0; })) continue;
      at::WdtParams params;
      params.downsample = factor;
      params.passes = 2;
      params.huMin = label == 2 ? -500.0f : -1000.0f;  // a second window: the density table is rebuilt
      params.rule = label == 3 ? StepRule::Trapezoid : StepRule::Entering;
      auto problem = at::prepareWdtProblem(ct, mask, params);
      REQUIRE(problem.has_value());
      const auto host = gpuField(*problem);
      at::WdtStats stats;
      auto field = at::cuda::runCudaBackendOnDevice(*uploaded, label, params, {}, &stats);
      REQUIRE_MESSAGE(field.has_value(), (field ? std::string() : field.error().message));
      CHECK(field->grid().dims == problem->grid.dims);
      CHECK(field->grid().spacingMm == problem->grid.spacingMm);
      CHECK(field->downsample() == factor);
      at::FloatVolume back;
      REQUIRE(at::cuda::copyToHost(*field, back).has_value());
      CAPTURE(factor);
      CAPTURE(label);
      CHECK_MESSAGE(sameBits(back.voxels, host), describeDifference(back.voxels, host, problem->grid.dims));
      CHECK(stats.passesRun == 2);
    }
  }
  auto missing = at::cuda::runCudaBackendOnDevice(*uploaded, 9, at::WdtParams{}, {}, nullptr);
  REQUIRE_FALSE(missing.has_value());
  CHECK(missing.error().message.find("label 9") != std::string::npos);
}
