// CUDA WDT kernel benchmark: one JSON line per (size, mode) with GPU time per pass (median over
// runs, from CUDA events), wall time per call, and accuracy against the CPU backend and the exact
// reference where affordable. The input is a synthetic head: air, a soft-tissue ball with noise,
// a dense skull shell and a few dense blobs, 0.2 mm voxels, seeds in a small central ball.
//
// Wall time is the whole runCudaBackend call; the warm-up call of each configuration allocates the
// backend's cached workspace, the measured calls reuse it.
//
//   wdt_cuda_bench [--sizes 128,256,512] [--reps 10] [--check-max 256] [--cpu-check-max 0]
//                  [--sweeps-before-bricks -1] [--z-planes Z] [--sweep-kernel groups,persistent,auto]
//
// --check-max: sizes up to this get the exact reference and the CPU backend beside the GPU;
// --cpu-check-max: sizes up to this (above --check-max) get the CPU backend only, for the
// bit-for-bit comparison on volumes where the exact reference takes too long. --z-planes Z: the
// central Z planes of each size's head only (n × n × Z voxels), e.g. just past 2³² voxels. Each line states the
// device memory the workspace held (device_mib_used: cudaMemGetInfo's used memory after the runs).
//
// Converge mode runs once per value of --sweeps-before-bricks (whole-volume passes before the
// brick rounds; see cuda/wdt_cuda.h). --sweep-kernel: each (size, mode) once per sweep kernel
// listed, in that order (groups: a launch per plane group; persistent: one launch a sweep where it
// fits; auto: the backend's default, persistent for the large tile only; see
// at::cuda::setPersistentSweeps); each line names it and how many sweeps its captured passes ran
// persistently. Without the option, the backend's default (AT_WDT_CUDA_PERSISTENT).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cuda/wdt_cuda.h"
#include "wdt/problem.h"

namespace {

// The head on an n³ grid, or its central nz planes along z (nz < n: a slab, the same voxels as
// those planes of the n³ head).
at::WdtProblem syntheticHead(int n, int nz) {
  at::WdtProblem p;
  p.grid.dims = {n, n, nz};
  const int z0 = (n - nz) / 2;
  p.grid.spacingMm = {51.2 / n, 51.2 / n, 51.2 / n};
  p.density.resize(p.grid.dims.count());
  p.seeds.assign(p.grid.dims.count(), 0);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> noise(0, 12);
  const double c = (n - 1) / 2.0;
  const double blobs[4][4] = {{0.3, 0.5, 0.5, 0.08}, {0.7, 0.45, 0.4, 0.06}, {0.5, 0.3, 0.65, 0.07}, {0.55, 0.7, 0.35, 0.05}};
  for (int kz = 0; kz < nz; ++kz)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const int k = kz + z0;
        const double r = std::sqrt((i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c)) / n;
        int q = 0;
        if (r < 0.40) q = 40 + noise(rng);
        else if (r < 0.46) q = 230 + noise(rng) / 2;
        for (const auto& b : blobs) {
          const double dx = double(i) / n - b[0], dy = double(j) / n - b[1], dz = double(k) / n - b[2];
          if (dx * dx + dy * dy + dz * dz < b[3] * b[3]) q = 250;
        }
        const std::size_t idx = p.grid.dims.index(i, j, kz);
        p.density[idx] = std::uint8_t(std::min(255, q));
        if (r < 3.0 / n + 1e-9) p.seeds[idx] = 1;
      }
  return p;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

double maxRelDiff(const std::vector<float>& a, const std::vector<float>& b) {
  double m = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i] == b[i]) continue;
    m = std::max(m, std::fabs(double(a[i]) - double(b[i])) / std::max(1e-30, std::fabs(double(b[i]))));
  }
  return m;
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

std::vector<int> parseList(const char* s) {
  std::vector<int> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(std::atoi(item.c_str()));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> sizes = {128, 256, 512};
  int reps = 10, checkMax = 256, cpuCheckMax = 0, zPlanes = 0;
  std::vector<int> sweepsBeforeBricks = {-1};  // the default
  std::vector<std::string> kernels = {""};     // "": the backend's default
  for (int a = 1; a + 1 < argc; a += 2) {
    const std::string flag = argv[a];
    if (flag == "--sizes") sizes = parseList(argv[a + 1]);
    else if (flag == "--reps") reps = std::max(1, std::atoi(argv[a + 1]));  // at least one measured run
    else if (flag == "--check-max") checkMax = std::atoi(argv[a + 1]);
    else if (flag == "--cpu-check-max") cpuCheckMax = std::atoi(argv[a + 1]);
    else if (flag == "--z-planes") zPlanes = std::atoi(argv[a + 1]);
    else if (flag == "--sweeps-before-bricks") sweepsBeforeBricks = parseList(argv[a + 1]);
    else if (flag == "--sweep-kernel") {
      kernels.clear();
      std::stringstream in(argv[a + 1]);
      for (std::string k; std::getline(in, k, ',');) {
        if (k != "groups" && k != "persistent" && k != "auto") {
          std::fprintf(stderr, "wdt_cuda_bench: --sweep-kernel: unknown kernel '%s' (groups, persistent or auto)\n",
                       k.c_str());
          return 2;
        }
        kernels.push_back(k);
      }
    }
    else {
      std::fprintf(stderr, "wdt_cuda_bench: unknown option %s\n", flag.c_str());
      return 2;
    }
  }
  const auto& device = at::cuda::queryDevice();
  if (!device.available) {
    std::printf("{\"bench\":\"wdt_cuda\",\"skipped\":\"%s\"}\n", device.reason.c_str());
    return 0;
  }
  for (int n : sizes) {
    const int nz = zPlanes > 0 && zPlanes < n ? zPlanes : n;
    at::WdtProblem p = syntheticHead(n, nz);
    const bool check = n <= checkMax;
    at::FloatVolume exact;
    if (check) {
      auto e = at::exactWdtOnProblem(p);
      if (!e) {
        std::fprintf(stderr, "%s\n", e.error().message.c_str());
        return 1;
      }
      exact = std::move(*e);
    }
    // (passes, or 0 = converge; passes before brick rounds, -1 = the default; unused for fixed passes)
    std::vector<std::pair<int, int>> runs = {{1, -1}, {2, -1}};
    for (int k : sweepsBeforeBricks) runs.push_back({0, k});
    // The CPU backend's field per mode (fixed passes: 1 or 2; converge: 0), made once for every
    // kernel and --sweeps-before-bricks value.
    std::map<int, at::WdtResult> cpuByMode;
    auto cpuField = [&](int mode) -> const at::WdtResult* {
      if (auto it = cpuByMode.find(mode); it != cpuByMode.end()) return &it->second;
      auto cpu = at::runCpuBackend(p, {});
      if (!cpu) {
        std::fprintf(stderr, "%s\n", cpu.error().message.c_str());
        return nullptr;
      }
      return &cpuByMode.emplace(mode, std::move(*cpu)).first->second;
    };
    for (const auto& [mode, sweepsFirst] : runs) {
      for (const std::string& kernel : kernels) {
        if (!kernel.empty()) {
          at::cuda::setPersistentSweeps(kernel == "persistent" ? at::cuda::PersistentSweeps::On
                                        : kernel == "groups"   ? at::cuda::PersistentSweeps::Off
                                                               : at::cuda::PersistentSweeps::Auto);
        }
        const long long capturedBefore = at::cuda::persistentSweepsCaptured();
        if (mode == 0) at::cuda::setConvergeSweepsBeforeBricks(sweepsFirst);
        p.params.converge = mode == 0;
        p.params.passes = mode == 0 ? 2 : mode;
        p.params.maxPasses = 64;
        std::vector<double> perPass, wall, device;
        at::WdtResult last;
        for (int r = 0; r < reps + 1; ++r) {  // the first run warms up
          last = {};  // one field on the host at a time (13.5 GiB at 1536³)
          auto res = at::cuda::runCudaBackend(p, {});
          if (!res) {
            std::fprintf(stderr, "%s\n", res.error().message.c_str());
            return 1;
          }
          if (r > 0) {
            for (double ms : res->stats.msPerPass) perPass.push_back(ms);
            device.push_back(res->stats.msCompute);
            wall.push_back(res->stats.msTotal);
          }
          last = std::move(*res);
        }
        std::printf("{\"bench\":\"wdt_cuda\",\"device\":\"%s\",\"size\":%d,\"z_planes\":%d,\"mode\":\"%s\",\"scheme\":\"%s\","
                    "\"passes_run\":%d,\"rounds\":%d,\"converged\":%s,\"ms_per_pass_median\":%.4f,"
                    "\"ms_device_median\":%.4f,\"ms_device_min\":%.4f,\"ms_device_max\":%.4f,\"ms_wall_median\":%.3f,"
                    "\"sweeps_before_bricks\":%d,\"runs\":%d",
                    last.stats.device.c_str(), n, nz, mode == 0 ? "converge" : (mode == 1 ? "1 pass" : "2 passes"),
                    last.stats.scheme.c_str(), last.stats.passesRun, last.stats.rounds,
                    last.stats.converged ? "true" : "false", median(perPass), median(device),
                    *std::min_element(device.begin(), device.end()), *std::max_element(device.begin(), device.end()),
                    median(wall), sweepsFirst, reps);
        std::printf(",\"sweep_kernel\":\"%s\",\"persistent_sweeps_captured\":%lld",
                    kernel.empty() ? "default" : kernel.c_str(), at::cuda::persistentSweepsCaptured() - capturedBefore);
        const double usedMiB = at::cuda::deviceMemoryUsedMiB();
        if (usedMiB >= 0) std::printf(",\"device_mib_used\":%.0f", usedMiB);
        const auto& g = last.field.distances.voxels;
        if (check || n <= cpuCheckMax) {
          const at::WdtResult* cpu = cpuField(mode);
          if (!cpu) return 1;
          const auto& c = cpu->field.distances.voxels;
          std::printf(",\"cpu_passes_run\":%d,\"gpu_equals_cpu_bitwise\":%s,\"max_rel_diff_gpu_cpu\":%.3g",
                      cpu->stats.passesRun, sameBits(g, c) ? "true" : "false", maxRelDiff(g, c));
          if (check) {
            const at::WdtAccuracy acc = at::compareToExact(last.field.distances, exact);
            const at::WdtAccuracy cacc = at::compareToExact(cpu->field.distances, exact);
            std::printf(",\"gpu_mean_rel_err\":%.3g,\"gpu_p99_rel_err\":%.3g,\"gpu_max_rel_err\":%.3g,\"gpu_below_exact\":%zu,"
                        "\"cpu_mean_rel_err\":%.3g,\"cpu_p99_rel_err\":%.3g,\"gpu_equals_exact_bitwise\":%s",
                        acc.meanRelErr, acc.p99RelErr, acc.maxRelErr, acc.belowExact, cacc.meanRelErr, cacc.p99RelErr,
                        sameBits(g, exact.voxels) ? "true" : "false");
          }
        }
        std::printf("}\n");
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
