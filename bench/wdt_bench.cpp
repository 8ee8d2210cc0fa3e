// wdt_bench: weighted distance transform timings and accuracy, one JSON line per configuration.
//
//   wdt_bench [--sizes 128,256,512] [--backends cpu,cuda] [--repeats 10] [--modes 1,2,converge]
//             [--sweeps-before-bricks N]   (CUDA converge: whole-volume passes before brick rounds)
//             [--structures cochlea,...] [--data DIR] [--no-real] [--exact-max 256] [--threads N]
//
// Datasets: the phantom at each size (seeded at each of --structures, the cochlea by default)
// and, when DIR/totalsegmentator holds ct_small.nii.gz and seg_small.nii.gz, the real abdominal CT
// seeded at the left kidney and at L1.
// Per configuration: one warm-up run, then `repeats` runs; ms_per_pass is the median over all
// passes of all runs (the backends time each pass: CPU wall clock, CUDA events), ms_total the
// median of the runs' totals. Accuracy against the exact reference (Dijkstra, timed once) where
// the grid has at most exact-max³ voxels. cpu_ms_total: median CPU time of the process per run
// (all threads), reported beside the wall-clock times because shared machines are often loaded.
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "volume/image_file.h"
#include "volume/mask.h"
#include "volume/nifti_io.h"
#include "volume/phantom.h"
#include "wdt/wdt.h"

#if defined(AT_HAVE_CUDA)
#include "cuda/wdt_cuda.h"
#endif

namespace {

using namespace at;

struct Options {
  std::vector<int> sizes{128, 256, 512};
  std::vector<std::string> backends{"cpu", "cuda"};
  std::vector<std::string> modes{"1", "2", "converge"};
  int repeats = 10;
  std::string dataDir = "../shared/data";
  bool real = true;
  int exactMax = 256;
  std::vector<std::string> structures{"cochlea"};  // phantom structures to seed at, one case each
};

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

std::optional<Options> parseOptions(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::optional<std::string> {
      if (i + 1 >= argc) return std::nullopt;
      return std::string(argv[++i]);
    };
    std::optional<std::string> v;
    if (a == "--no-real") {
      o.real = false;
      continue;
    }
    if (a == "--help" || a == "-h") return std::nullopt;
    if (!(v = next())) {
      std::fprintf(stderr, "wdt_bench: option %s needs a value\n", a.c_str());
      return std::nullopt;
    }
    if (a == "--sizes") {
      o.sizes.clear();
      for (const std::string& s : split(*v)) o.sizes.push_back(std::atoi(s.c_str()));
    } else if (a == "--backends") {
      o.backends = split(*v);
    } else if (a == "--modes") {
      o.modes = split(*v);
    } else if (a == "--repeats") {
      o.repeats = std::max(1, std::atoi(v->c_str()));
    } else if (a == "--data") {
      o.dataDir = *v;
    } else if (a == "--structures") {
      o.structures = split(*v);
    } else if (a == "--exact-max") {
      o.exactMax = std::atoi(v->c_str());
    } else if (a == "--sweeps-before-bricks") {
#if defined(AT_HAVE_CUDA)
      cuda::setConvergeSweepsBeforeBricks(std::atoi(v->c_str()));  // CUDA converge mode (cuda/wdt_cuda.h)
#endif
    } else if (a == "--threads") {
      setenv("AT_WDT_THREADS", v->c_str(), 1);
    } else {
      std::fprintf(stderr, "wdt_bench: unknown option %s\n", a.c_str());
      return std::nullopt;
    }
  }
  return o;
}

// CPU time of the whole process (all threads) in ms: on a loaded machine this stays close to the
// uncontended cost while wall-clock times stretch with the load.
double processCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

double loadAverage() {
  double l = -1;
  if (FILE* f = std::fopen("/proc/loadavg", "r")) {
    if (std::fscanf(f, "%lf", &l) != 1) l = -1;
    std::fclose(f);
  }
  return l;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

struct Case {
  std::string dataset, structure;
  Volume volume;
  Mask seeds;
};

void runCase(const Case& c, const Options& o) {
  const Dims d = c.volume.dims();
  const bool exactAffordable = double(d.count()) <= double(o.exactMax) * o.exactMax * o.exactMax;
  std::optional<FloatVolume> exact;
  double exactMs = 0, exactCpuMs = 0;
  for (const std::string& backendName : o.backends) {
    auto backend = parseBackend(backendName);
    if (!backend) {
      std::fprintf(stderr, "wdt_bench: %s\n", backend.error().message.c_str());
      continue;
    }
#if defined(AT_HAVE_CUDA)
    if (*backend == WdtBackend::Cuda && !cuda::queryDevice().available) {
      std::printf("{\"bench\":\"wdt\",\"dataset\":%s,\"backend\":\"cuda\",\"skipped\":%s}\n", jsonString(c.dataset).c_str(),
                  jsonString("no CUDA device: " + cuda::queryDevice().reason).c_str());
      continue;
    }
#else
    if (*backend == WdtBackend::Cuda) {
      std::printf("{\"bench\":\"wdt\",\"dataset\":%s,\"backend\":\"cuda\",\"skipped\":\"built without CUDA\"}\n",
                  jsonString(c.dataset).c_str());
      continue;
    }
#endif
    for (const std::string& mode : o.modes) {
      WdtParams p;
      p.backend = *backend;
      if (mode == "converge") {
        p.converge = true;
      } else {
        p.passes = std::max(1, std::atoi(mode.c_str()));
      }
      auto warm = computeWdt(c.volume, c.seeds, p);
      if (!warm) {
        std::printf("{\"bench\":\"wdt\",\"dataset\":%s,\"backend\":%s,\"error\":%s}\n", jsonString(c.dataset).c_str(),
                    jsonString(backendName).c_str(), jsonString(warm.error().message).c_str());
        break;
      }
      std::vector<double> perPass, totals, cpuTotals, compute;
      WdtResult last = std::move(*warm);
      for (int r = 0; r < o.repeats; ++r) {
        const double cpu0 = processCpuMs();
        auto run = computeWdt(c.volume, c.seeds, p);
        if (!run) break;
        cpuTotals.push_back(processCpuMs() - cpu0);
        perPass.insert(perPass.end(), run->stats.msPerPass.begin(), run->stats.msPerPass.end());
        totals.push_back(run->stats.msTotal);
        compute.push_back(run->stats.msCompute);
        last = std::move(*run);
      }
      std::string accuracy;
      if (exactAffordable) {
        if (!exact) {
          const auto t0 = std::chrono::steady_clock::now();
          const double cpu0 = processCpuMs();
          auto e = exactWdt(c.volume, c.seeds, p);
          exactMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
          exactCpuMs = processCpuMs() - cpu0;
          if (e) exact = std::move(*e);
        }
        if (exact) {
          const WdtAccuracy a = compareToExact(last.field.distances, *exact);
          char buf[400];
          std::snprintf(buf, sizeof buf,
                        ",\"mean_rel_err\":%.3g,\"p99_rel_err\":%.3g,\"max_rel_err\":%.3g,\"exact_fraction\":%.6f,"
                        "\"below_exact\":%zu,\"exact_ms\":%.1f,\"exact_cpu_ms\":%.1f",
                        a.meanRelErr, a.p99RelErr, a.maxRelErr, a.exactFraction, a.belowExact, exactMs, exactCpuMs);
          accuracy = buf;
        }
      }
      std::printf(
          "{\"bench\":\"wdt\",\"dataset\":%s,\"structure\":%s,\"dims\":[%d,%d,%d],\"backend\":%s,\"device\":%s,"
          "\"mode\":%s,\"scheme\":%s,\"passes_run\":%d,\"rounds\":%d,\"converged\":%s,\"runs\":%zu,"
          "\"ms_per_pass\":%.3f,\"ms_compute\":%.3f,\"ms_total\":%.3f,"
          "\"ms_total_min\":%.3f,\"cpu_ms_total\":%.3f,\"load_avg\":%.2f%s}\n",
          jsonString(c.dataset).c_str(), jsonString(c.structure).c_str(), d.x, d.y, d.z,
          jsonString(toString(last.stats.backendUsed)).c_str(), jsonString(last.stats.device).c_str(),
          jsonString(mode).c_str(), jsonString(last.stats.scheme).c_str(), last.stats.passesRun, last.stats.rounds,
          last.stats.converged ? "true" : "false", totals.size(), median(perPass), median(compute), median(totals),
          totals.empty() ? 0.0 : *std::min_element(totals.begin(), totals.end()), median(cpuTotals), loadAverage(),
          accuracy.c_str());
      std::fflush(stdout);
    }
  }
}

std::optional<Case> realCase(const Options& o, const std::string& labelName) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(o.dataDir) / "totalsegmentator";
  const fs::path ct = dir / "ct_small.nii.gz", seg = dir / "seg_small.nii.gz", names = dir / "labels.json";
  if (!fs::exists(ct) || !fs::exists(seg) || !fs::exists(names)) return std::nullopt;
  auto img = loadNifti(ct.string());
  auto lab = loadNifti(seg.string());
  auto nameMap = loadLabelNames(names.string());
  if (!img || !lab || !nameMap) {
    std::fprintf(stderr, "wdt_bench: cannot load the real CT from %s\n", dir.c_str());
    return std::nullopt;
  }
  auto hu = toHuVolume(*img, ct.string());
  auto labels = toLabelMap(*lab, seg.string());
  if (!hu || !labels || !(labels->dims() == hu->dims())) return std::nullopt;
  std::optional<std::uint16_t> value;
  for (const auto& [v, n] : *nameMap)
    if (n == labelName) value = v;
  if (!value) return std::nullopt;
  Case c{"ct_small", labelName, std::move(*hu), structureMask(*labels, *value)};
  c.seeds.geometry = c.volume.geometry;
  if (measureMask(c.seeds).voxelCount == 0) return std::nullopt;
  return c;
}

}  // namespace

int main(int argc, char** argv) {
  auto options = parseOptions(argc, argv);
  if (!options) {
    std::fprintf(stderr,
                 "usage: wdt_bench [--sizes 128,256,512] [--backends cpu,cuda] [--repeats 10] "
                 "[--modes 1,2,converge] [--structures cochlea,...] [--data DIR] [--no-real] [--exact-max 256] [--threads N]\n");
    return 2;
  }
  for (int size : options->sizes) {
    PhantomOptions po;
    po.size = size;
    Dataset ds = makePhantom(po);
    for (const std::string& id : options->structures) {
      const Structure* s = ds.findStructure(id);
      if (!s) {
        std::string known;
        for (const Structure& k : ds.structures) known += (known.empty() ? "" : ", ") + k.id;
        std::fprintf(stderr, "wdt_bench: --structures: the phantom has no structure '%s' (it has %s)\n", id.c_str(),
                     known.c_str());
        return 2;
      }
      Case c{"phantom:" + std::to_string(size), s->id, ds.volume, structureMask(ds.labels, s->label)};
      runCase(c, *options);
    }
  }
  if (options->real) {
    for (const char* label : {"kidney_left", "vertebrae_L1"})
      if (auto c = realCase(*options, label)) runCase(*c, *options);
  }
  return 0;
}
