// CPU sweeps against the exact reference on fresh random volumes, downsampling, cancellation,
// progress, errors.
#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <random>

#include "test_support.h"
#include "wdt/problem.h"
#include "wdt/wdt.h"

using namespace at;

namespace {

struct RandomCase {
  Volume volume;
  Mask seeds;
  WdtParams params;
};

// Random HU (blocky, so that walls and channels appear), random spacing, 1–3 seeds, random rule.
RandomCase randomCase(std::mt19937_64& rng, Dims dims) {
  Geometry g;
  g.dims = dims;
  std::uniform_real_distribution<double> sp(0.3, 1.5);
  g.spacingMm = {sp(rng), sp(rng), sp(rng)};
  RandomCase c{Volume(g), Mask(g, 0), {}};
  std::uniform_int_distribution<int> hu(-1000, 2000), block(1, 4);
  const int b = block(rng);
  std::vector<std::int16_t> blockHu(std::size_t((dims.x / b + 1) * (dims.y / b + 1) * (dims.z / b + 1)));
  for (auto& h : blockHu) h = std::int16_t(hu(rng));
  for (int k = 0; k < dims.z; ++k)
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i) {
        const std::size_t bi = std::size_t(i / b + (dims.x / b + 1) * (j / b + (dims.y / b + 1) * (k / b)));
        c.volume.at(i, j, k) = std::int16_t(std::clamp(blockHu[bi] + hu(rng) / 10, -1024, 3000));
      }
  std::uniform_int_distribution<int> nSeeds(1, 3);
  for (int s = nSeeds(rng); s > 0; --s)
    c.seeds.at(std::uniform_int_distribution<int>(0, dims.x - 1)(rng), std::uniform_int_distribution<int>(0, dims.y - 1)(rng),
               std::uniform_int_distribution<int>(0, dims.z - 1)(rng)) = 1;
  c.params.backend = WdtBackend::Cpu;
  const WeightRule weights[] = {WeightRule::Density, WeightRule::Density, WeightRule::Uniform, WeightRule::Gradient,
                                WeightRule::Ascent};
  c.params.weight = weights[std::uniform_int_distribution<int>(0, 4)(rng)];
  c.params.rule = std::uniform_int_distribution<int>(0, 1)(rng) ? StepRule::Trapezoid : StepRule::Entering;
  // A base cost of 0 makes air steps free (and the exact reference use its heap instead of buckets).
  c.params.baseCost = std::uniform_int_distribution<int>(0, 3)(rng) == 0 ? 0.0f
                                                                          : std::uniform_real_distribution<float>(0.0f, 0.2f)(rng);
  return c;
}

}  // namespace

TEST_CASE("CPU sweeps are never below the exact reference, improve with every pass and converge to it") {
  std::mt19937_64 rng(test::freshSeed("sweeps vs exact"));
  const Dims sizes[] = {{1, 1, 1}, {2, 2, 2}, {1, 17, 9}, {31, 31, 31}, {33, 20, 7}, {33, 33, 33}, {5, 1, 40}, {64, 9, 3}};
  for (const Dims& dims : sizes) {
    RandomCase c = randomCase(rng, dims);
    CAPTURE(dims.toString());
    CAPTURE(toString(c.params.rule));
    CAPTURE(toString(c.params.weight));
    CAPTURE(c.params.baseCost);
    auto exact = exactWdt(c.volume, c.seeds, c.params);
    REQUIRE(exact);
    std::vector<float> previous;
    for (int passes = 1; passes <= 3; ++passes) {
      c.params.passes = passes;
      auto r = computeWdt(c.volume, c.seeds, c.params);
      REQUIRE(r);
      CHECK(r->stats.passesRun == passes);
      const auto& d = r->field.distances.voxels;
      std::size_t below = 0, worse = 0;
      for (std::size_t i = 0; i < d.size(); ++i) {
        below += d[i] < exact->voxels[i];
        if (!previous.empty()) worse += d[i] > previous[i];
      }
      CHECK(below == 0);
      CHECK(worse == 0);
      previous = d;
    }
    c.params.converge = true;
    auto conv = computeWdt(c.volume, c.seeds, c.params);
    REQUIRE(conv);
    CHECK(conv->stats.converged);
    const WdtAccuracy acc = compareToExact(conv->field.distances, *exact);
    CHECK(acc.belowExact == 0);
    CHECK(acc.maxRelErr <= 1e-6);
    for (std::size_t i = 0; i < exact->voxels.size(); ++i)
      if (std::isinf(exact->voxels[i])) CHECK(std::isinf(conv->field.distances.voxels[i]));
  }
}

TEST_CASE("Forced 2 and 3 threads give the same field as one thread, bit for bit") {
  std::mt19937_64 rng(test::freshSeed("threads"));
  const Dims sizes[] = {{33, 20, 7}, {17, 40, 31}, {3, 2, 9}};
  for (const Dims& dims : sizes) {
    RandomCase c = randomCase(rng, dims);
    CAPTURE(dims.toString());
    c.params.passes = 2;
    std::vector<std::vector<float>> fields;
    for (const char* threads : {"1", "2", "3"}) {
      setenv("AT_WDT_THREADS", threads, 1);
      auto r = computeWdt(c.volume, c.seeds, c.params);
      unsetenv("AT_WDT_THREADS");
      REQUIRE(r);
      CHECK(r->stats.device == std::string("CPU (") + threads + (threads[0] == '1' ? " thread)" : " threads)"));
      fields.push_back(r->field.distances.voxels);
    }
    CHECK(fields[1] == fields[0]);
    CHECK(fields[2] == fields[0]);
  }
}

TEST_CASE("A downsampled field stays within a block's reach of the full field after upsampling") {
  // Uniform weights, unit spacing: the coarse field differs from the full one by the seed's
  // dilation to its block (≤ (F−1)·√3 mm) plus interpolation (≤ F·√3 mm across a coarse voxel).
  Geometry g;
  g.dims = {40, 36, 30};
  Volume v(g, std::int16_t(0));
  Mask m(g, 0);
  m.at(11, 20, 7) = 1;
  WdtParams p;
  p.backend = WdtBackend::Cpu;
  p.weight = WeightRule::Uniform;
  p.converge = true;
  auto full = computeWdt(v, m, p);
  REQUIRE(full);
  for (int f : {2, 3, 4}) {
    CAPTURE(f);
    p.downsample = f;
    auto coarse = computeWdt(v, m, p);
    REQUIRE(coarse);
    const Dims cd = coarse->field.distances.dims();
    CHECK(cd == Dims{(40 + f - 1) / f, (36 + f - 1) / f, (30 + f - 1) / f});
    CHECK(coarse->field.downsample == f);
    CHECK(coarse->field.distances.geometry.spacingMm[0] == doctest::Approx(f));
    const FloatVolume up = upsampleField(coarse->field, g);
    const double bound = (2 * f - 1) * std::sqrt(3.0);
    double worst = 0;
    for (std::size_t i = 0; i < up.voxels.size(); ++i)
      worst = std::max(worst, std::abs(double(up.voxels[i]) - full->field.distances.voxels[i]));
    CHECK(worst <= bound);
  }
}

TEST_CASE("Downsampling keeps a one-voxel bone wall closed (blocks take their densest voxel)") {
  Geometry g;
  g.dims = {32, 16, 16};
  Volume v(g, std::int16_t(-1000));
  for (int k = 0; k < 16; ++k)
    for (int j = 0; j < 16; ++j) v.at(17, j, k) = 2000;
  Mask m(g, 0);
  m.at(8, 8, 8) = 1;
  WdtParams p;
  p.backend = WdtBackend::Cpu;
  p.converge = true;
  auto full = computeWdt(v, m, p);
  REQUIRE(full);
  p.downsample = 4;
  auto coarse = computeWdt(v, m, p);
  REQUIRE(coarse);
  const FloatVolume up = upsampleField(coarse->field, g);
  // Behind the wall the full field has paid the wall (≥ 1.02 mm·weight); so must the coarse one.
  CHECK(full->field.distances.at(24, 8, 8) > 1.0f);
  CHECK(up.at(24, 8, 8) >= 0.9f * full->field.distances.at(24, 8, 8));
  auto problem = prepareWdtProblem(v, m, p);
  REQUIRE(problem);
  CHECK(problem->density[problem->grid.dims.index(4, 2, 2)] == 255);  // block x 16..19 holds the wall
  CHECK(problem->seeds[problem->grid.dims.index(2, 2, 2)] == 1);
}

TEST_CASE("Cancellation returns early with cancelled set and a field never below the exact one") {
  Geometry g;
  g.dims = {24, 24, 24};
  Volume v(g);
  for (std::size_t i = 0; i < v.voxels.size(); ++i) v.voxels[i] = std::int16_t(int(i * 2654435761u % 3000) - 1000);
  Mask m(g, 0);
  m.at(3, 3, 3) = 1;
  WdtParams p;
  p.backend = WdtBackend::Cpu;
  p.passes = 6;
  auto exact = exactWdt(v, m, p);
  REQUIRE(exact);

  std::atomic<bool> cancel{true};
  WdtControl control;
  control.cancel = &cancel;
  auto r = computeWdt(v, m, p, control);
  REQUIRE(r);
  CHECK(r->stats.cancelled);
  CHECK(r->stats.passesRun == 0);
  CHECK_FALSE(r->stats.converged);

  cancel = false;
  std::vector<int> seen;
  control.progress = [&](int done, int planned) {
    seen.push_back(done);
    CHECK(planned == 6);
    if (done == 2) cancel = true;
  };
  auto partial = computeWdt(v, m, p, control);
  REQUIRE(partial);
  CHECK(partial->stats.cancelled);
  CHECK(partial->stats.passesRun == 2);
  CHECK(seen == std::vector<int>{1, 2});
  CHECK(compareToExact(partial->field.distances, *exact).belowExact == 0);
}

TEST_CASE("Stats report passes, per-pass times and the CPU device") {
  Geometry g;
  g.dims = {16, 16, 16};
  Volume v(g, std::int16_t(0));
  Mask m(g, 0);
  m.at(0, 0, 0) = 1;
  WdtParams p;
  p.backend = WdtBackend::Cpu;
  p.passes = 3;
  auto r = computeWdt(v, m, p);
  REQUIRE(r);
  CHECK(r->stats.passesRun == 3);
  CHECK(r->stats.msPerPass.size() == 3);
  CHECK((r->stats.backendUsed == WdtBackend::Cpu));
  CHECK(r->stats.device.rfind("CPU (", 0) == 0);
  CHECK(r->stats.warning.empty());
  CHECK(r->stats.msTotal >= r->stats.msPerPass[0]);
}

TEST_CASE("Bad params, an empty mask and a mask on another grid are errors naming the problem") {
  Geometry g;
  g.dims = {8, 8, 8};
  Volume v(g, std::int16_t(0));
  Mask m(g, 0);
  m.at(1, 1, 1) = 1;
  auto expectError = [&](const WdtParams& p, const Mask& mask, const std::string& needle) {
    auto r = computeWdt(v, mask, p);
    REQUIRE_FALSE(r);
    CAPTURE(r.error().message);
    CHECK(r.error().message.find(needle) != std::string::npos);
  };
  WdtParams p;
  p.backend = WdtBackend::Cpu;
  WdtParams bad = p;
  bad.passes = 0;
  expectError(bad, m, "passes");
  bad = p;
  bad.downsample = 0;
  expectError(bad, m, "downsample");
  bad = p;
  bad.huMax = bad.huMin;
  expectError(bad, m, "huMax");
  bad = p;
  bad.baseCost = -0.1f;
  expectError(bad, m, "baseCost");
  bad = p;
  bad.maxPasses = 0;
  expectError(bad, m, "maxPasses");
  expectError(p, Mask(g, 0), "structure mask is empty");
  Geometry other = g;
  other.dims = {8, 8, 7};
  Mask wrong(other, 1);
  expectError(p, wrong, "8x8x7");
  CHECK_FALSE(exactWdt(v, Mask(g, 0), p));
}

TEST_CASE("The cuda backend either runs or says why it cannot") {
  Geometry g;
  g.dims = {8, 8, 8};
  Volume v(g, std::int16_t(0));
  Mask m(g, 0);
  m.at(1, 1, 1) = 1;
  WdtParams p;
  p.backend = WdtBackend::Cuda;
  auto r = computeWdt(v, m, p);
  if (r) {
    CHECK((r->stats.backendUsed == WdtBackend::Cuda));
  } else {
    CAPTURE(r.error().message);
    CHECK((r.error().message.find("CUDA") != std::string::npos || r.error().message.find("cuda") != std::string::npos));
  }
  p.backend = WdtBackend::Auto;
  auto autoRun = computeWdt(v, m, p);
  REQUIRE(autoRun);
  CHECK(autoRun->field.distances.at(1, 1, 1) == 0.0f);
}

TEST_CASE("Param names round-trip through toString and parse") {
  for (StepRule r : {StepRule::Entering, StepRule::Trapezoid}) CHECK((*parseStepRule(toString(r)) == r));
  for (WeightRule w : {WeightRule::Density, WeightRule::Uniform, WeightRule::Gradient, WeightRule::Ascent})
    CHECK((*parseWeightRule(toString(w)) == w));
  for (WdtBackend b : {WdtBackend::Auto, WdtBackend::Cpu, WdtBackend::Cuda}) CHECK((*parseBackend(toString(b)) == b));
  CHECK_FALSE(parseStepRule("midpoint"));
  CHECK(parseWeightRule("opacity").error().message.find("opacity") != std::string::npos);
  CHECK_FALSE(parseBackend("gpu"));
}

TEST_CASE("Upsampling an unreachable corner takes the nearest value instead of blending infinity") {
  Geometry g;
  g.dims = {2, 1, 1};
  g.spacingMm = {2, 2, 2};
  DistanceField f;
  f.distances = FloatVolume(g);
  f.distances.voxels = {1.0f, std::numeric_limits<float>::infinity()};
  f.downsample = 2;
  Geometry t;
  t.dims = {9, 1, 1};
  t.spacingMm = {0.5, 2, 2};
  const FloatVolume up = upsampleField(f, t);
  CHECK(up.at(0, 0, 0) == 1.0f);
  CHECK(up.at(1, 0, 0) == 1.0f);   // x = 0.5 mm: nearer to the finite corner at 0 mm
  CHECK(std::isinf(up.at(3, 0, 0)));  // x = 1.5 mm: nearer to the unreachable one at 2 mm
  CHECK(std::isinf(up.at(8, 0, 0)));  // beyond the field: clamped to its last voxel
  f.distances.voxels = {1.0f, 3.0f};
  const FloatVolume lin = upsampleField(f, t);
  CHECK(lin.at(1, 0, 0) == doctest::Approx(1.5f));
  CHECK(lin.at(2, 0, 0) == doctest::Approx(2.0f));
}
