// anatomy-tutor segment DATASET --seeds SEEDS.json --out LABELS: labels a dataset from a user's
// seed strokes (grow from seeds, or threshold islands) through the segment editor's model, writes
// the label map (NIfTI with a names JSON, or Slicer .seg.nrrd), and optionally saves it into the
// dataset store or compares it with reference labels (Dice per label).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>

#include "cli_args.h"
#include "commands.h"
#include "core/strings.h"
#include "dataset_options.h"
#include "label_output.h"
#include "segment/growth_settings.h"
#include "segment/label_editor.h"
#include "segment/ranged_growth.h"
#include "segment/seeds.h"
#include "volume/label_writers.h"
#include "wdt/label_growth.h"
#include "printable_output.h"

namespace at::app {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const char* kUsage =
    "usage: anatomy-tutor segment DATASET --seeds SEEDS.json --out LABELS.nii.gz|LABELS.seg.nrrd\n"
    "                             [--names NAMES.json] [--method grow|threshold] [--backend auto|cpu|cuda]\n"
    "                             [--weight gradient|density|uniform|ascent] [--window LO,HI] [--base B]\n"
    "                             [--smoothing S] [--range LO,HI|bone] [--compare] [--save] [--json]\n"
    "  Labels DATASET from seed strokes. SEEDS.json lists labels ({\"value\", \"name\"}, value 0 being\n"
    "  the background) and strokes in mm ({\"label\", \"points\": [[x,y,z], ...], \"radius_mm\"}); the\n"
    "  format is documented in segment/include/segment/seeds.h.\n"
    "  --method grow       (default) every voxel takes the label of the seed with the smallest\n"
    "                      weighted distance; needs strokes of two or more labels (background included)\n"
    "  --method threshold  each label with a \"range\" takes the connected region of values in that range\n"
    "                      under its first point (\"min_diameter_mm\" cuts thinner bridges)\n"
    "  --weight            step cost of the growth: gradient (intensity difference, default), density,\n"
    "                      uniform or ascent; --window LO,HI the values mapped to 0..1 (default: the\n"
    "                      dataset's window: -1000,2000 HU for CT, the histogram window for plain\n"
    "                      intensities); --base B the cost per mm added to every step (default: from the\n"
    "                      data's step noise and voxel size, segment/growth_settings.h; printed);\n"
    "                      --smoothing S edge-preserving smoothing before growth, sigma in voxels\n"
    "                      (0 none; default 1 where the data are noisy)\n"
    "  A label's \"grow_range\" ([LO, HI] or \"bone\") keeps it to voxels in that range, grown by a\n"
    "                      second growth limited to it (segment/ranged_growth.h)\n"
    "  --range             grow only into voxels whose value lies in LO..HI (HU or intensities; others\n"
    "                      keep label 0 unless seeded); 'bone' takes the range derived from the data\n"
    "                      (300 HU and up for CT; a pseudo-HU bone threshold for plain intensities)\n"
    "  --out               .nii/.nii.gz: uint16 label map; .seg.nrrd: a 3D Slicer segmentation\n"
    "  --names             also write { \"value\": \"name\" } for the labels\n"
    "  --compare           Dice of each label against the dataset's own labels (the built-in phantom's,\n"
    "                      or --labels FILE, matched by label value): they are never shown to the growth\n"
    "  --save              store the labels in the dataset store (imported datasets)\n";

Result<std::array<double, 2>> parsePair(const std::string& option, const std::string& text) {
  const auto comma = text.find(',');
  char* end = nullptr;
  if (comma != std::string::npos) {
    const std::string a = text.substr(0, comma), b = text.substr(comma + 1);
    const double lo = std::strtod(a.c_str(), &end);
    const bool ok = !a.empty() && *end == '\0';
    const double hi = std::strtod(b.c_str(), &end);
    if (ok && !b.empty() && *end == '\0' && lo < hi) return std::array<double, 2>{lo, hi};
  }
  return fail("option --" + option + ": '" + text + "' is not LO,HI with LO < HI");
}

// The growth's parameters: command line over the seeds file over the defaults.
Result<GrowthParams> growthParams(const cli::Args& args, const segment::SeedSet& seeds, const Dataset& dataset) {
  const segment::GrowthDefaults defaults = segment::defaultGrowthSettings(dataset.volume, dataset.intensity);
  GrowthParams p = defaults.params;
  auto backend = parseBackend(args.valueOr("backend", "auto"));
  if (!backend) return tl::unexpected(backend.error());
  p.backend = *backend;
  const std::string weight = args.valueOr("weight", seeds.grow.weight.value_or("gradient"));
  auto rule = parseWeightRule(weight);
  if (!rule) return tl::unexpected(rule.error());
  p.weight = *rule;
  auto base = args.number("base", seeds.grow.base.value_or(double(p.baseCost)));
  if (!base) return tl::unexpected(base.error());
  p.baseCost = float(*base);
  auto smoothing = args.number("smoothing", seeds.grow.smoothing.value_or(double(p.smoothingVoxels)));
  if (!smoothing) return tl::unexpected(smoothing.error());
  p.smoothingVoxels = float(*smoothing);
  std::array<double, 2> window{dataset.intensity.valueOf(dataset.intensity.window[0]),
                               dataset.intensity.valueOf(dataset.intensity.window[1])};
  if (seeds.grow.window) window = *seeds.grow.window;
  if (auto text = args.value("window")) {
    auto parsed = parsePair("window", *text);
    if (!parsed) return tl::unexpected(parsed.error());
    window = *parsed;
  }
  // The window is given in the dataset's values; the growth maps stored values.
  const IntensityModel& m = dataset.intensity;
  p.windowMin = float((window[0] - m.intercept) / m.slope);
  p.windowMax = float((window[1] - m.intercept) / m.slope);
  if (seeds.grow.range) p = segment::withRangeLimit(p, m, *seeds.grow.range);
  if (auto text = args.value("range")) {
    std::array<double, 2> range = defaults.boneRangeValues;
    if (*text != "bone") {
      auto parsed = parsePair("range", *text);
      if (!parsed) return tl::unexpected(parsed.error());
      range = *parsed;
    }
    p = segment::withRangeLimit(p, m, range);
  }
  if (auto ok = validateGrowthParams(p); !ok) return tl::unexpected(ok.error());
  return p;
}

// The structures the seed labels become (the background, value 0, is none).
std::vector<Structure> structuresOf(const segment::SeedSet& seeds) {
  std::vector<Structure> out;
  for (const segment::SeedLabel& l : seeds.labels) {
    if (l.value == 0) continue;
    Structure s;
    s.label = l.value;
    s.id = str::identifier(l.name);
    s.displayName = displayNameOf(l.name);
    s.colour = l.colour.value_or(paletteColour(l.value));
    out.push_back(s);
  }
  return out;
}

// --save: the labels into the dataset store (imported datasets).
Result<std::string> saveToStore(const cli::Args& args, const std::string& datasetName, const LabelMap& labels,
                                const std::vector<Structure>& structures) {
  auto database = db::openDatabase(args.db());
  if (!database) return tl::unexpected(database.error());
  auto saved = storeDatasetLabels(*database, datasetName, labels, structures);
  if (!saved) return tl::unexpected(withContext("--save", saved.error()));
  return saved;
}

double dice(const LabelMap& a, const LabelMap& b, std::uint16_t label, std::size_t& inA, std::size_t& inB) {
  std::size_t both = 0;
  inA = inB = 0;
  for (std::size_t i = 0; i < a.voxels.size(); ++i) {
    const bool x = a.voxels[i] == label, y = b.voxels[i] == label;
    inA += x, inB += y, both += x && y;
  }
  return inA + inB == 0 ? 1.0 : 2.0 * double(both) / double(inA + inB);
}

}  // namespace

int runSegment(const Argv& argv) {
  auto args = cli::Args::parse(
      argv, withDatasetOptions({"seeds", "out", "names", "method", "backend", "weight", "window", "base", "smoothing", "range"}),
      {"compare", "save", "json"});
  if (!args) return reportError("segment: " + args.error().message, 2);
  if (args->has("help")) {
    terminalPrintf("%s", kUsage);
    return 0;
  }
  if (args->positional().size() != 1) return reportError("segment: expected one DATASET (see --help)", 2);
  const auto seedsPath = args->value("seeds");
  if (!seedsPath) return reportError("segment: --seeds SEEDS.json is required", 2);
  const auto out = args->value("out");
  if (!out) return reportError("segment: --out LABELS.nii.gz is required", 2);
  if (auto ok = checkLabelsPath(*out); !ok) return reportError("segment: " + ok.error().message, 2);
  const std::string method = args->valueOr("method", "grow");
  if (method != "grow" && method != "threshold")
    return reportError("segment: --method must be grow or threshold, not '" + method + "'", 2);

  auto seeds = segment::loadSeeds(*seedsPath);
  if (!seeds) return reportError("segment: " + seeds.error().message);
  // --names is this command's output (the names of the labels it writes), not the names of the
  // reference label map of --labels: the comparison goes by label value.
  DatasetRequest request = datasetRequestFrom(*args, args->positional()[0]);
  request.namesPath.clear();
  auto dataset = openNamedDataset(request);
  if (!dataset) return reportError("segment: " + dataset.error().message);
  reportDatasetWarnings(*dataset);
  if (args->has("compare") && dataset->structures.empty())
    return reportError("segment: --compare needs the dataset's own labels (--labels FILE for a volume file)");
  auto raster = segment::rasteriseSeeds(*seeds, dataset->volume.geometry);
  if (!raster) return reportError("segment: " + *seedsPath + ": " + raster.error().message);

  segment::LabelEditor editor(LabelMap(dataset->volume.geometry, 0), structuresOf(*seeds));
  const auto t0 = std::chrono::steady_clock::now();
  GrowthStats stats;
  std::string how;
  if (method == "grow") {
    if (auto ok = segment::requireTwoSeededLabels(*seeds, *raster); !ok)
      return reportError("segment: " + *seedsPath + ": " + ok.error().message);
    auto params = growthParams(*args, *seeds, *dataset);
    if (!params) return reportError("segment: " + params.error().message, 2);
    applyDatasetWindow(*dataset, params->windowMin, params->windowMax, true, params->weight == WeightRule::Density);
    // Labels with a "grow_range" keep only their range's voxels (segment/ranged_growth.h), through
    // the editor's growth as in the desktop's segment editor.
    const auto bone = segment::defaultGrowthSettings(dataset->volume, dataset->intensity).boneRangeValues;
    const segment::LabelRanges ranges{dataset->intensity, segment::labelRangesOf(*seeds, bone)};
    auto grown = editor.growFromSeeds(dataset->volume, raster->seeds, *params, &stats, ranges);
    if (!grown) return reportError("segment: " + grown.error().message);
    if (!stats.warning.empty()) terminalFprintf(stderr, "anatomy-tutor: segment: %s\n", stats.warning.c_str());
    char base[64];
    std::snprintf(base, sizeof base, ", base %.4g/mm", double(params->baseCost));
    how = std::string("grow from seeds, ") + toString(params->weight) + " weights" + base + ", " + stats.device;
  } else {
    how = "threshold islands";
    for (const segment::SeedStroke& stroke : seeds->strokes) {
      const segment::SeedLabel& label = seeds->labels[stroke.label];
      if (label.value == 0) continue;
      if (!label.range)
        return reportError("segment: " + *seedsPath + ": label '" + label.name + "' needs a \"range\" for --method threshold");
      segment::ThresholdOptions options;
      options.minDiameterMm = label.minDiameterMm;
      auto island = editor.thresholdIsland(dataset->volume, dataset->intensity, stroke.pointsMm.front(),
                                           (*label.range)[0], (*label.range)[1], label.value, options);
      if (!island) return reportError("segment: label '" + label.name + "': " + island.error().message);
    }
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();

  if (auto ok = writeLabelsFile(*out, editor.labels(), editor.structures()); !ok) return reportError("segment: " + ok.error().message);
  if (auto names = args->value("names"))
    if (auto ok = writeLabelNames(*names, editor.structures()); !ok) return reportError("segment: " + ok.error().message);
  std::string saved;
  if (args->has("save")) {
    auto path = saveToStore(*args, args->positional()[0], editor.labels(), editor.structures());
    if (!path) return reportError("segment: " + path.error().message);
    saved = *path;
  }

  // The table: per seed label, its seed voxels, voxels labelled, and (--compare) Dice.
  const std::size_t total = editor.labels().voxels.size();
  json rows = json::array();
  for (std::size_t i = 0; i < seeds->labels.size(); ++i) {
    const segment::SeedLabel& l = seeds->labels[i];
    std::size_t labelled = 0, reference = 0;
    const double d = dice(editor.labels(), dataset->labels, l.value, labelled, reference);
    json row{{"value", l.value}, {"name", l.name}, {"seed_voxels", raster->perLabel[i]}, {"voxels", labelled}};
    if (args->has("compare")) {
      row["reference_voxels"] = reference;
      row["dice"] = d;
    }
    rows.push_back(row);
  }
  json report{{"dataset", dataset->id},
              {"method", method},
              {"seed_voxels", raster->seeds.size()},
              {"seeded_fraction", double(raster->seeds.size()) / double(total)},
              {"ms", ms},
              {"labels", rows},
              {"out", *out}};
  if (method == "grow")
    report["growth"] = {{"backend", toString(stats.backendUsed)}, {"device", stats.device},
                        {"brick_visits", stats.brickVisits}, {"ms_compute", stats.msCompute}};
  if (!saved.empty()) report["saved"] = saved;
  if (args->has("json")) {
    std::printf("%s\n", report.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace).c_str());
    return 0;
  }
  terminalPrintf("%s: %s, %zu seed voxels (%.4f %% of %zu), %.0f ms\n", dataset->id.c_str(), how.c_str(),
              raster->seeds.size(), 100.0 * double(raster->seeds.size()) / double(total), total, ms);
  terminalPrintf("%6s  %-28s %10s %10s%s\n", "label", "name", "seeds", "voxels", args->has("compare") ? "  reference    Dice" : "");
  for (const json& row : rows) {
    terminalPrintf("%6d  %-28s %10zu %10zu", row["value"].get<int>(), row["name"].get<std::string>().c_str(),
                row["seed_voxels"].get<std::size_t>(), row["voxels"].get<std::size_t>());
    if (args->has("compare"))
      terminalPrintf(" %10zu  %6.3f", row["reference_voxels"].get<std::size_t>(), row["dice"].get<double>());
    terminalPrintf("\n");
  }
  terminalPrintf("wrote %s%s%s\n", out->c_str(), args->has("names") ? (" and " + *args->value("names")).c_str() : "",
              saved.empty() ? "" : (", saved " + saved).c_str());
  return 0;
}

}  // namespace at::app
