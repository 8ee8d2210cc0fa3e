// Shared by the CUDA WDT tests (test_wdt_cuda*.cpp): random problems, the GPU and CPU fields,
// bitwise and relative comparisons, and the fixed-pass check against the CPU backend.
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "cuda/wdt_cuda.h"
#include "test_support.h"
#include "wdt/problem.h"

namespace wdt_cuda_cases {

using at::StepRule;
using at::WdtProblem;
using at::WeightRule;

inline bool requireDevice() {
  const auto& info = at::cuda::queryDevice();
  if (!info.available) {
    at::test::skipf("no CUDA device (%s)", info.reason.c_str());
    return false;
  }
  return true;
}

// A random problem: density bytes mixing smooth regions, noise and dense slabs, a few seeds.
inline WdtProblem randomProblem(std::mt19937_64& rng, at::Dims dims, at::Vec3 spacing, StepRule rule, WeightRule weight) {
  WdtProblem p;
  p.grid.dims = dims;
  p.grid.spacingMm = spacing;
  const std::size_t n = dims.count();
  p.density.resize(n);
  p.seeds.assign(n, 0);
  std::uniform_int_distribution<int> byte(0, 255);
  std::uniform_real_distribution<double> unit(0, 1);
  const double fx = 0.1 + unit(rng) * 0.4, fy = 0.1 + unit(rng) * 0.4, fz = 0.1 + unit(rng) * 0.4;
  const int slab = dims.x > 4 ? int(unit(rng) * dims.x) : -1;
  for (int k = 0; k < dims.z; ++k)
    for (int j = 0; j < dims.y; ++j)
      for (int i = 0; i < dims.x; ++i) {
        const double smooth = 0.5 + 0.5 * std::sin(fx * i) * std::cos(fy * j + fz * k);
        int q = int(smooth * 200) + byte(rng) / 8;
        if (i == slab && (j + k) % 7 != 0) q = 255;  // a dense wall with holes
        p.density[dims.index(i, j, k)] = std::uint8_t(std::min(255, q));
      }
  const int seeds = 1 + int(unit(rng) * 3);
  for (int s = 0; s < seeds; ++s) {
    p.seeds[std::size_t(unit(rng) * double(n)) % n] = 1;
  }
  p.params.rule = rule;
  p.params.weight = weight;
  p.params.baseCost = 0.02f + float(unit(rng)) * 0.2f;
  return p;
}

inline std::vector<float> gpuField(const WdtProblem& p, at::WdtStats* stats = nullptr) {
  auto r = at::cuda::runCudaBackend(p, {});
  REQUIRE_MESSAGE(r.has_value(), (r ? std::string() : r.error().message));
  if (stats) *stats = r->stats;
  return r->field.distances.voxels;
}

inline std::vector<float> cpuField(const WdtProblem& p) {
  auto r = at::runCpuBackend(p, {});
  REQUIRE_MESSAGE(r.has_value(), (r ? std::string() : r.error().message));
  return r->field.distances.voxels;
}

inline double relDiff(float a, float b) {
  if (a == b) return 0;  // equal infinities included
  if (std::isinf(a) || std::isinf(b)) return std::numeric_limits<double>::infinity();
  return std::fabs(double(a) - double(b)) / std::max(1e-30, std::fabs(double(b)));
}

inline double maxRelDiff(const std::vector<float>& a, const std::vector<float>& b) {
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) m = std::max(m, relDiff(a[i], b[i]));
  return m;
}

// Voxels where a < b·(1 − tol) (a below b beyond rounding).
inline std::size_t countBelow(const std::vector<float>& a, const std::vector<float>& b, double tol) {
  std::size_t c = 0;
  for (std::size_t i = 0; i < a.size(); ++i) c += double(a[i]) < double(b[i]) * (1 - tol);
  return c;
}

inline bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// For failure messages: how many voxels differ and the first one (index and both values, exact).
inline std::string describeDifference(const std::vector<float>& gpu, const std::vector<float>& cpu, const at::Dims& dims) {
  if (gpu.size() != cpu.size()) return "sizes differ";
  std::size_t count = 0, first = 0;
  for (std::size_t i = 0; i < gpu.size(); ++i)
    if (std::memcmp(&gpu[i], &cpu[i], sizeof(float)) != 0 && count++ == 0) first = i;
  if (count == 0) return "identical";
  char buf[200];
  std::snprintf(buf, sizeof buf, "%zu voxels differ; first at (%zu,%zu,%zu): gpu %.9g cpu %.9g", count,
                first % std::size_t(dims.x), (first / std::size_t(dims.x)) % std::size_t(dims.y),
                first / (std::size_t(dims.x) * std::size_t(dims.y)), double(gpu[first]), double(cpu[first]));
  return buf;
}

// After 1 and 2 passes the GPU field must equal the CPU backend's bit for bit.
inline void checkFixedPassesMatchCpu(WdtProblem p) {
  const at::Dims dims = p.grid.dims;
  CAPTURE(dims.toString());
  const std::string ruleName = at::toString(p.params.rule);
  CAPTURE(ruleName);
  const std::string weightName = at::toString(p.params.weight);
  CAPTURE(weightName);
  for (int passes = 1; passes <= 2; ++passes) {
    p.params.passes = passes;
    const auto gpu = gpuField(p), cpu = cpuField(p);
    CHECK_MESSAGE(sameBits(gpu, cpu), describeDifference(gpu, cpu, dims) << " after " << passes << " pass(es)");
  }
}

inline const StepRule kRules[] = {StepRule::Entering, StepRule::Trapezoid};
inline const WeightRule kWeights[] = {WeightRule::Density, WeightRule::Uniform, WeightRule::Gradient, WeightRule::Ascent};

inline const at::Dims kEdgeSizes[] = {{1, 1, 1}, {2, 2, 2}, {31, 31, 31}, {33, 33, 33}, {33, 17, 65}, {1, 40, 3},
                               {70, 1, 9},  {5, 9, 1}, {40, 37, 2}};

}  // namespace wdt_cuda_cases
