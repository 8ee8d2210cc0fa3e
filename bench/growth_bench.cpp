// Grow-from-seeds benchmark (label_growth.h): one JSON line per (size, backend, step) with the
// update's wall time, compute time, brick visits and rounds. The input is the built-in phantom at
// N³ (the same anatomy in mm at every size) with 8 labels: strokes inside 7 structures and in the
// background, drawn as a user would: six short strokes (up to 8 voxels along x) a label, ~350 seed
// voxels (0.015 % of the voxels at 128³, 0.002 % at 256³). Steps, each timed on the same
// LabelGrowth:
//   first      the growth from scratch (the first update after create)
//   add        one more background stroke next to a structure (an interactive edit)
//   erase      that stroke removed again (its label's voxels reset and regrown)
//   relabel    one structure's strokes given another label
// Each step is run --reps times on a fresh growth (add/erase/relabel after a fresh first update) and
// the median reported; `exact` (sizes up to --check-max) says whether the final labels equal the
// exact reference's.
//
//   growth_bench [--sizes 128,256] [--backends cpu,cuda] [--reps 3] [--check-max 128]
//
// Memory per voxel (bench/RESULTS.md): the engine's 64-bit key and density byte, the host label
// map (2 bytes) and the caller's volume (2 bytes). ms_cpu is the process's CPU time (all threads)
// during the update: on a shared machine the wall time also holds other jobs' time.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "volume/phantom.h"
#include "wdt/label_growth.h"

namespace {

using namespace at;

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

std::vector<std::string> splitList(const char* s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  std::string item;
  while (std::getline(in, item, ',')) out.push_back(item);
  return out;
}

// Strokes: for each label, lines of voxels along x through voxels of that label, every `gap`-th
// voxel of a label's sorted voxel list starting a stroke of up to 8 voxels that stays in the label.
std::vector<GrowthSeed> strokeSeeds(const LabelMap& labels, const std::vector<std::uint16_t>& wanted,
                                    std::uint16_t background, int strokesPerLabel) {
  const Dims d = labels.dims();
  std::map<std::uint16_t, std::vector<std::size_t>> voxels;
  for (std::size_t i = 0; i < labels.voxels.size(); ++i) {
    const std::uint16_t l = labels.voxels[i];
    if (l == 0 || std::find(wanted.begin(), wanted.end(), l) != wanted.end()) voxels[l].push_back(i);
  }
  std::vector<GrowthSeed> seeds;
  for (const auto& [label, list] : voxels) {
    const std::size_t gap = std::max<std::size_t>(1, list.size() / std::size_t(strokesPerLabel + 1));
    for (std::size_t s = gap / 2; s < list.size(); s += gap) {
      std::size_t i = list[s];
      for (int t = 0; t < 8 && labels.voxels[i] == label; ++t, ++i) {
        seeds.push_back({i, label == 0 ? background : label});
        if ((i + 1) % std::size_t(d.x) == 0) break;
      }
    }
  }
  return seeds;
}

// CPU time of the whole process (all threads), in ms: on a shared machine the wall time also
// counts the time other people's jobs held the cores.
double processCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

struct StepResult {
  std::vector<double> wall, compute, cpu;
  std::size_t visits = 0, reset = 0;
  int rounds = 0;
  std::string device;
};

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> sizes = {"128", "256"}, backends = {"cpu"};
  int reps = 3, checkMax = 128;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(stderr, "growth_bench: %s needs a value\n", a.c_str());
      return 2;
    }
    if (a == "--sizes") sizes = splitList(argv[++i]);
    else if (a == "--backends") backends = splitList(argv[++i]);
    else if (a == "--reps") reps = std::max(1, std::atoi(argv[++i]));
    else if (a == "--check-max") checkMax = std::atoi(argv[++i]);
    else {
      std::fprintf(stderr, "growth_bench: unknown option %s (see the comment at the top of bench/growth_bench.cpp)\n",
                   a.c_str());
      return 2;
    }
  }
  for (const std::string& sizeText : sizes) {
    const int n = std::atoi(sizeText.c_str());
    PhantomOptions options;
    options.size = n;
    const Dataset phantom = makePhantom(options);
    // 7 structures and the background: 8 labels (background is label 0).
    const std::vector<std::uint16_t> structures = {1, 2, 7, 8, 9, 14, 15};
    const std::vector<GrowthSeed> seeds = strokeSeeds(phantom.labels, structures, 0, 6);
    // The interactive edit: a background stroke of 10 voxels along y beside the cochlea (label 1).
    std::vector<GrowthSeed> withStroke = seeds;
    {
      std::size_t first = 0;
      for (std::size_t i = 0; i < phantom.labels.voxels.size(); ++i)
        if (phantom.labels.voxels[i] == 1) {
          first = i;
          break;
        }
      const Dims d = phantom.labels.dims();
      const int x = int(first % std::size_t(d.x)), y = int((first / std::size_t(d.x)) % std::size_t(d.y)),
                z = int(first / (std::size_t(d.x) * std::size_t(d.y)));
      for (int t = 0; t < 10 && y - 2 - t >= 0; ++t) {
        const std::size_t i = d.index(x, y - 2 - t, z);
        if (phantom.labels.voxels[i] == 0 &&
            std::none_of(seeds.begin(), seeds.end(), [&](const GrowthSeed& s) { return s.index == i; }))
          withStroke.push_back({i, 0});
      }
    }
    std::vector<GrowthSeed> relabelled = seeds;
    for (GrowthSeed& s : relabelled)
      if (s.label == 9) s.label = 8;  // the tympanic cavity's strokes marked as external canal
    const double seededFraction = double(seeds.size()) / double(phantom.volume.voxels.size());

    for (const std::string& backendText : backends) {
      auto backend = parseBackend(backendText);
      if (!backend) {
        std::fprintf(stderr, "growth_bench: %s\n", backend.error().message.c_str());
        return 2;
      }
      GrowthParams params;
      params.backend = *backend;
      params.weight = WeightRule::Gradient;
      params.baseCost = 0.01f;
      std::map<std::string, StepResult> steps;
      bool exactEqual = true;
      bool checked = false;
      for (int rep = 0; rep < reps; ++rep) {
        auto growth = LabelGrowth::create(phantom.volume, params);
        if (!growth) {
          std::fprintf(stderr, "growth_bench: %s\n", growth.error().message.c_str());
          return 1;
        }
        auto run = [&](const char* name, const std::vector<GrowthSeed>& s) -> bool {
          const double cpu0 = processCpuMs();
          auto stats = growth->update(s);
          const double cpu = processCpuMs() - cpu0;
          if (!stats) {
            std::fprintf(stderr, "growth_bench: %s\n", stats.error().message.c_str());
            return false;
          }
          StepResult& r = steps[name];
          r.wall.push_back(stats->msTotal);
          r.compute.push_back(stats->msCompute);
          r.cpu.push_back(cpu);
          r.visits = stats->brickVisits;
          r.rounds = stats->rounds;
          r.reset = stats->voxelsReset;
          r.device = stats->device;
          return true;
        };
        if (!run("first", seeds) || !run("add", withStroke) || !run("erase", seeds) || !run("relabel", relabelled))
          return 1;
        if (rep == 0 && n <= checkMax) {
          checked = true;
          auto exact = exactLabelGrowth(phantom.volume, relabelled, params);
          if (!exact) return 1;
          exactEqual = exact->labels.voxels == growth->labels().voxels;
        }
      }
      for (const char* name : {"first", "add", "erase", "relabel"}) {
        const StepResult& r = steps[name];
        std::printf(
            "{\"size\": %d, \"backend\": \"%s\", \"device\": \"%s\", \"labels\": 8, \"seeds\": %zu, "
            "\"seeded_fraction\": %.6f, \"step\": \"%s\", \"ms_wall\": %.2f, \"ms_compute\": %.2f, \"ms_cpu\": %.1f, "
            "\"brick_visits\": %zu, "
            "\"rounds\": %d, \"voxels_reset\": %zu, \"reps\": %d, \"exact_equal\": %s}\n",
            n, backendText.c_str(), r.device.c_str(), seeds.size(), seededFraction, name, median(r.wall),
            median(r.compute), median(r.cpu), r.visits, r.rounds, r.reset, reps,
            checked ? (exactEqual ? "true" : "false") : "null");
        std::fflush(stdout);
      }
    }
  }
  return 0;
}
