// The CPU backend after N passes against the sweeps written out plainly (one voxel at a time, in
// the order x+ x− y+ y− z+ z−, every voxel from its 9 neighbours in the previous plane through
// wdt::relaxVoxel, the per-voxel update the row kernels must reproduce): equal bit for bit. The
// backend reorganises memory (transposed copies for the x sweeps, transposes folded
// into sweeps, initial state built directly in the transposed layout), vectorises and splits rows
// among threads; none of that may change a single float. AT_WDT_NO_AVX2 switches the backend to
// its baseline code so that both the AVX2 and the SSE2 kernels, transposes and set-up are checked.
#include <doctest/doctest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>

#include "test_support.h"
#include "wdt/problem.h"
#include "wdt/stencil.h"
#include "wdt/step_cost.h"
#include "wdt/wdt.h"

using namespace at;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Sweep along grid axis `axis` in direction dir; the plane axes are (b, c) as in axisSweepLengths.
template <wdt::CostKernel K>
void plainSweep(std::vector<float>& D, const std::vector<std::uint8_t>& q, Dims d, int axis, int dir,
                wdt::SweepLengths l, float base) {
  const int n[3] = {d.x, d.y, d.z};
  const int b = axis == 0 ? 1 : 0, c = axis == 2 ? 1 : 2;
  auto index = [&](const int v[3]) { return std::size_t(v[0]) + std::size_t(d.x) * (v[1] + std::size_t(d.y) * v[2]); };
  for (int step = 1; step < n[axis]; ++step) {
    const int p = dir > 0 ? step : n[axis] - 1 - step;
    for (int vc = 0; vc < n[c]; ++vc)
      for (int vb = 0; vb < n[b]; ++vb) {
        int v[3];
        v[axis] = p;
        v[b] = vb;
        v[c] = vc;
        float nb[3][3];
        std::uint8_t qn[3][3];
        for (int dc = 0; dc < 3; ++dc)
          for (int db = 0; db < 3; ++db) {
            int u[3];
            u[axis] = p - dir;
            u[b] = vb + db - 1;
            u[c] = vc + dc - 1;
            const bool inside = u[b] >= 0 && u[b] < n[b] && u[c] >= 0 && u[c] < n[c];
            nb[dc][db] = inside ? D[index(u)] : kInf;
            qn[dc][db] = inside ? q[index(u)] : 0;
          }
        const std::size_t i = index(v);
        D[i] = wdt::relaxVoxel<K>(D[i], nb, qn, q[i], l, base);
      }
  }
}

template <wdt::CostKernel K>
std::vector<float> plainPasses(const WdtProblem& pr, int passes) {
  const Dims d = pr.grid.dims;
  std::vector<float> D(d.count());
  for (std::size_t i = 0; i < D.size(); ++i) D[i] = pr.seeds[i] ? 0.0f : kInf;
  const float sx = float(pr.grid.spacingMm[0]), sy = float(pr.grid.spacingMm[1]), sz = float(pr.grid.spacingMm[2]);
  for (int pass = 0; pass < passes; ++pass)
    for (int axis = 0; axis < 3; ++axis)
      for (int dir : {+1, -1})
        plainSweep<K>(D, pr.density, d, axis, dir, wdt::axisSweepLengths(axis, sx, sy, sz), pr.params.baseCost);
  return D;
}

std::vector<float> plainPasses(const WdtProblem& pr, int passes) {
  return wdt::withCostKernel(wdt::costKernel(pr.params),
                              [&]<wdt::CostKernel K>() { return plainPasses<K>(pr, passes); });
}

// Random blocky HU, random spacing, a few seeds (some on the volume's faces), random weight rule.
std::pair<Volume, Mask> randomVolume(std::mt19937_64& rng, Dims dims) {
  Geometry g;
  g.dims = dims;
  std::uniform_real_distribution<double> sp(0.4, 1.6);
  g.spacingMm = {sp(rng), sp(rng), sp(rng)};
  Volume v(g);
  Mask m(g, 0);
  std::uniform_int_distribution<int> hu(-1000, 2000), block(1, 3);
  const int bs = block(rng);
  const int bx = dims.x / bs + 1, by = dims.y / bs + 1, bz = dims.z / bs + 1;
  std::vector<int> blockHu(std::size_t(bx) * by * bz);
  for (int& h : blockHu) h = hu(rng);
  for (int k = 0; k < dims.z; ++k)
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i)
        v.at(i, j, k) = std::int16_t(blockHu[std::size_t(i / bs + bx * (j / bs + by * (k / bs)))] + hu(rng) / 20);
  for (int s = std::uniform_int_distribution<int>(1, 4)(rng); s > 0; --s)
    m.at(std::uniform_int_distribution<int>(0, dims.x - 1)(rng), std::uniform_int_distribution<int>(0, dims.y - 1)(rng),
         std::uniform_int_distribution<int>(0, dims.z - 1)(rng)) = 1;
  return {std::move(v), std::move(m)};
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

}  // namespace

TEST_CASE("After 1, 2 and 3 passes the CPU backend equals the plainly written sweeps bit for bit, on 1 to 3 threads, "
          "with and without AVX2") {
  std::mt19937_64 rng(test::freshSeed("fixed-pass sweeps vs plain"));
  // Sizes around the 8-wide tiles and vectors of the transposes and row kernels: multiples of 8,
  // ragged edges, one-voxel axes, x − 1 a multiple of 8.
  const Dims sizes[] = {{37, 29, 19}, {9, 9, 9}, {16, 24, 8}, {8, 17, 33}, {1, 12, 10}, {23, 1, 6}, {70, 45, 6}};
  const WeightRule weights[] = {WeightRule::Density, WeightRule::Uniform, WeightRule::Gradient, WeightRule::Ascent};
  int n = 0;
  for (const Dims& dims : sizes) {
    auto [volume, mask] = randomVolume(rng, dims);
    WdtParams params;
    params.backend = WdtBackend::Cpu;
    // The entering density rule (the product's default) on every other size, the rest in turn.
    params.weight = n % 2 == 0 ? WeightRule::Density : weights[(n / 2) % 4];
    params.rule = n % 4 == 3 ? StepRule::Trapezoid : StepRule::Entering;
    params.baseCost = std::uniform_real_distribution<float>(0.005f, 0.1f)(rng);
    ++n;
    CAPTURE(dims.toString());
    CAPTURE(toString(params.weight));
    CAPTURE(toString(params.rule));
    for (int passes = 1; passes <= 3; ++passes) {
      params.passes = passes;
      auto problem = prepareWdtProblem(volume, mask, params);
      REQUIRE(problem);
      const std::vector<float> expected = plainPasses(*problem, passes);
      for (const char* threads : {"1", "2", "3"})
        for (const bool baseline : {false, true}) {
          CAPTURE(passes);
          CAPTURE(threads);
          CAPTURE(baseline);
          setenv("AT_WDT_THREADS", threads, 1);
          if (baseline) setenv("AT_WDT_NO_AVX2", "1", 1);
          auto r = runCpuBackend(*problem, {});
          unsetenv("AT_WDT_THREADS");
          unsetenv("AT_WDT_NO_AVX2");
          REQUIRE(r);
          CHECK(r->stats.passesRun == passes);
          CHECK(sameBits(r->field.distances.voxels, expected));
        }
    }
  }
}

TEST_CASE("Cancelled before the first pass, the CPU backend returns the seeds' starting field") {
  std::mt19937_64 rng(test::freshSeed("cancel before first pass"));
  auto [volume, mask] = randomVolume(rng, {19, 11, 9});
  WdtParams params;
  params.backend = WdtBackend::Cpu;
  params.passes = 2;
  auto problem = prepareWdtProblem(volume, mask, params);
  REQUIRE(problem);
  std::atomic<bool> cancel{true};
  WdtControl control;
  control.cancel = &cancel;
  for (const char* threads : {"1", "2"}) {
    CAPTURE(threads);
    setenv("AT_WDT_THREADS", threads, 1);
    auto r = runCpuBackend(*problem, control);
    unsetenv("AT_WDT_THREADS");
    REQUIRE(r);
    CHECK(r->stats.cancelled);
    CHECK(r->stats.passesRun == 0);
    CHECK(sameBits(r->field.distances.voxels, plainPasses(*problem, 0)));
  }
}
