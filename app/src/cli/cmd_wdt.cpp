// anatomy-tutor wdt DATASET STRUCTURE [options]: computes a structure's weighted distance field,
// optionally checks it against the exact reference and writes it as NIfTI.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_args.h"
#include "commands.h"
#include "dataset_options.h"
#include "volume/dataset_source.h"
#include "volume/mask.h"
#include "volume/nifti_io.h"
#include "wdt/wdt.h"
#include "printable_output.h"

namespace at::app {

namespace {

constexpr const char* kUsage =
    "usage: anatomy-tutor wdt DATASET STRUCTURE [options]\n"
    "  Weighted distance field of STRUCTURE (id or name) through the CT densities.\n"
    "  DATASET: phantom | phantom:N (the built-in phantom at N^3), skull (scripts/fetch-scans.sh), an\n"
    "           imported dataset (--db PATH), or a volume file (.nii[.gz], .nrrd, .inv3) or DICOM folder,\n"
    "           whose structures come from:\n"
    "  --labels FILE               its label map (any volume format or DICOM SEG)\n"
    "  --names NAMES.json          names of the label values ({\"1\": \"spleen\", ...})\n"
    "  --series UID                the DICOM series to open, where a folder holds several\n"
    "  --backend auto|cpu|cuda     (default auto: CUDA when available, else CPU)\n"
    "  --passes N | --converge     fixed passes (default 2) or until a pass changes nothing\n"
    "  --rule entering|trapezoid   step cost w(b)|step| or (w(a)+w(b))/2 |step|\n"
    "  --weight density|uniform|gradient|ascent\n"
    "  --hu-window LO,HI           values mapped to density 0..1 (default -1000,2000 HU for CT; the\n"
    "                              dataset's histogram window for plain intensities, e.g. µCT, MR)\n"
    "  --base B                    base cost added to every weight (default 0.02)\n"
    "  --downsample F              compute on a grid F times coarser per axis\n"
    "  --check                     compare with the exact reference (Dijkstra) on the full grid;\n"
    "                              a downsampled field is upsampled to the dataset grid first\n"
    "  --out FIELD.nii.gz          write the field (upsampled to the dataset grid) as float32 NIfTI\n"
    "  --json                      one JSON object on stdout\n";

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

Result<WdtParams> paramsFrom(const cli::Args& args) {
  WdtParams p;
  if (auto v = args.value("backend")) {
    auto b = parseBackend(*v);
    if (!b) return tl::unexpected(b.error());
    p.backend = *b;
  }
  if (auto v = args.value("rule")) {
    auto r = parseStepRule(*v);
    if (!r) return tl::unexpected(r.error());
    p.rule = *r;
  }
  if (auto v = args.value("weight")) {
    auto w = parseWeightRule(*v);
    if (!w) return tl::unexpected(w.error());
    p.weight = *w;
  }
  if (args.has("converge") && args.has("passes")) return fail("--passes and --converge exclude each other");
  p.converge = args.has("converge");
  auto passes = args.integer("passes", p.passes);
  if (!passes) return tl::unexpected(passes.error());
  p.passes = *passes;
  auto downsample = args.integer("downsample", p.downsample);
  if (!downsample) return tl::unexpected(downsample.error());
  p.downsample = *downsample;
  auto base = args.number("base", p.baseCost);
  if (!base) return tl::unexpected(base.error());
  p.baseCost = float(*base);
  if (auto w = args.value("hu-window")) {
    const auto comma = w->find(',');
    char* end = nullptr;
    const std::string lo = comma == std::string::npos ? "" : w->substr(0, comma);
    const std::string hi = comma == std::string::npos ? "" : w->substr(comma + 1);
    const double l = std::strtod(lo.c_str(), &end);
    const bool loOk = !lo.empty() && *end == '\0';
    const double h = std::strtod(hi.c_str(), &end);
    const bool hiOk = !hi.empty() && *end == '\0';
    if (!loOk || !hiOk) return fail("option --hu-window: '" + *w + "' is not LO,HI (e.g. -1000,2000)");
    p.huMin = float(l);
    p.huMax = float(h);
  }
  if (auto ok = validateWdtParams(p); !ok) return tl::unexpected(ok.error());
  return p;
}

nlohmann::json dimsJson(const Dims& d) { return nlohmann::json::array({d.x, d.y, d.z}); }

}  // namespace

int runWdt(const Argv& argv) {
  auto parsed = cli::Args::parse(
      argv, withDatasetOptions({"backend", "passes", "rule", "weight", "hu-window", "base", "downsample", "out"}),
      withDatasetFlags({"converge", "check", "json"}));
  if (!parsed) return reportError("wdt: " + parsed.error().message);
  const cli::Args& args = *parsed;
  if (args.has("help")) {
    terminalPrintf("%s", kUsage);
    return 0;
  }
  if (args.positional().size() != 2) return reportError("wdt: expected DATASET STRUCTURE (see wdt --help)");
  auto params = paramsFrom(args);
  if (!params) return reportError("wdt: " + params.error().message);

  const std::string datasetName = args.positional()[0], structureName = args.positional()[1];
  auto dataset = openNamedDataset(datasetRequestFrom(args, datasetName));
  if (!dataset) return reportError("wdt: " + dataset.error().message);
  reportDatasetWarnings(*dataset);
  const Structure* structure = dataset->findStructure(structureName);
  if (!structure) return reportError("wdt: " + unknownStructureMessage(*dataset, structureName));
  const Mask mask = structureMask(dataset->labels, structure->label);
  applyDatasetWindow(*dataset, params->huMin, params->huMax, args.has("hu-window"),
                     params->weight != WeightRule::Uniform);

  auto result = computeWdt(dataset->volume, mask, *params);
  if (!result) return reportError("wdt: " + result.error().message);
  const WdtStats& stats = result->stats;
  if (!stats.warning.empty()) terminalFprintf(stderr, "anatomy-tutor: warning: %s\n", stats.warning.c_str());

  const bool downsampled = result->field.downsample > 1;
  FloatVolume onDatasetGrid;
  if (downsampled && (args.has("check") || args.has("out")))
    onDatasetGrid = upsampleField(result->field, dataset->volume.geometry);
  const FloatVolume& fullField = downsampled ? onDatasetGrid : result->field.distances;

  nlohmann::json out;
  out["dataset"] = dataset->id;
  out["structure"] = structure->id;
  out["backend"] = toString(stats.backendUsed);
  out["device"] = stats.device;
  out["dims"] = dimsJson(dataset->volume.dims());
  out["field_dims"] = dimsJson(result->field.distances.dims());
  out["rule"] = toString(params->rule);
  out["weight"] = toString(params->weight);
  out["downsample"] = params->downsample;
  out["scheme"] = stats.scheme;
  out["passes_run"] = stats.passesRun;
  if (stats.scheme != "sweeps") out["rounds"] = stats.rounds;
  out["converged"] = stats.converged;
  out["ms_total"] = stats.msTotal;
  out["ms_compute"] = stats.msCompute;
  // Brick rounds have no passes: null rather than a made-up time per pass.
  out["ms_per_pass"] = stats.msPerPass.empty() ? nlohmann::json(nullptr) : nlohmann::json(median(stats.msPerPass));
  if (!stats.warning.empty()) out["warning"] = stats.warning;

  if (args.has("check")) {
    const auto t0 = std::chrono::steady_clock::now();
    auto exact = exactWdt(dataset->volume, mask, *params);
    if (!exact) return reportError("wdt: " + exact.error().message);
    const double exactMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const WdtAccuracy acc = compareToExact(fullField, *exact);
    out["mean_rel_err"] = acc.meanRelErr;
    out["p99_rel_err"] = acc.p99RelErr;
    out["max_rel_err"] = acc.maxRelErr;
    out["exact_fraction"] = acc.exactFraction;
    out["below_exact"] = acc.belowExact;
    out["compared"] = acc.compared;
    out["exact_ms"] = exactMs;
  }

  if (auto path = args.value("out")) {
    if (auto ok = writeNiftiFloat(*path, fullField); !ok) return reportError("wdt: " + ok.error().message);
    out["out"] = *path;
  }

  if (args.has("json")) {
    std::printf("%s\n", out.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace).c_str());
    return 0;
  }
  terminalPrintf("%s / %s: %s rule, %s weights, %s on %s\n", dataset->id.c_str(), structure->id.c_str(),
              toString(params->rule), toString(params->weight), toString(stats.backendUsed), stats.device.c_str());
  const Dims fd = result->field.distances.dims();
  if (stats.scheme != "sweeps") {
    terminalPrintf("field %s (dataset %s), %d pass%s + %d brick round%s%s, %.1f ms total, %.2f ms computing\n",
                fd.toString().c_str(), dataset->volume.dims().toString().c_str(), stats.passesRun,
                stats.passesRun == 1 ? "" : "es", stats.rounds, stats.rounds == 1 ? "" : "s",
                stats.converged ? ", converged" : "", stats.msTotal, stats.msCompute);
  } else {
    terminalPrintf("field %s (dataset %s), %d pass%s%s, %.1f ms total, %.2f ms per pass (median)\n",
                fd.toString().c_str(), dataset->volume.dims().toString().c_str(), stats.passesRun,
                stats.passesRun == 1 ? "" : "es", stats.converged ? ", converged" : "", stats.msTotal,
                median(stats.msPerPass));
  }
  if (args.has("check"))
    terminalPrintf("vs exact (%.0f ms): mean rel err %.3g, p99 %.3g, max %.3g, exact %.2f %%, below exact %zu of %zu\n",
                out["exact_ms"].get<double>(), out["mean_rel_err"].get<double>(), out["p99_rel_err"].get<double>(),
                out["max_rel_err"].get<double>(), 100 * out["exact_fraction"].get<double>(),
                out["below_exact"].get<std::size_t>(), out["compared"].get<std::size_t>());
  if (args.has("out")) terminalPrintf("wrote %s\n", args.value("out")->c_str());
  return 0;
}

}  // namespace at::app
