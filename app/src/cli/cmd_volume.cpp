// Volume commands: datasets, structures, info, slice (ARCHITECTURE.md §7).
// Datasets are opened by name ("phantom", "phantom:N") or from files (a DATASET path, or
// --volume PATH with optional --labels PATH, --names JSON, --series UID).
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cli_args.h"
#include "core/printable_text.h"
#include "core/strings.h"
#include "commands.h"
#include "dataset_options.h"
#include "dataset_resolver.h"
#include "db/connection.h"
#include "db/dataset_store.h"
#include "volume/dataset_source.h"
#include "volume/image_file.h"
#include "volume/intensity.h"
#include "volume/known_scans.h"
#include "volume/phantom.h"
#include "volume/png_image.h"
#include "volume/slice_image.h"
#include "printable_output.h"

namespace at::app {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// --- shared helpers ----------------------------------------------------------------------------

// The volume commands' dataset options: the shared ones and --volume PATH (instead of DATASET).
const std::set<std::string> kDatasetOptions = withDatasetOptions({"volume"});

std::set<std::string> with(std::set<std::string> a, const std::set<std::string>& b) {
  a.insert(b.begin(), b.end());
  return a;
}

// Opens the dataset named by the arguments: a built-in name, an imported dataset, a path (file or
// DICOM folder), or --volume PATH. --labels, --names and --series apply to files only.
Result<Dataset> openDatasetArg(const cli::Args& args) {
  const auto& pos = args.positional();
  const auto volume = args.value("volume");
  if (volume && !pos.empty()) return fail("give either DATASET or --volume PATH, not both");
  if (!volume && pos.empty()) return fail("missing DATASET (a built-in name such as 'phantom', or a path)");
  if (pos.size() > 1) return fail("unexpected argument '" + pos[1] + "' (one DATASET only)");
  auto dataset = openNamedDataset(datasetRequestFrom(args, volume ? *volume : pos[0]));
  if (dataset) reportDatasetWarnings(*dataset);
  return dataset;
}

std::vector<std::size_t> labelHistogram(const LabelMap& labels) {
  std::vector<std::size_t> counts(65536, 0);
  for (std::uint16_t v : labels.voxels) ++counts[v];
  return counts;
}

std::string formatDouble(double v, int decimals = 3) {
  if (std::abs(v) < 0.5 * std::pow(10.0, -decimals)) v = 0;  // no "-0.000"
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

std::string formatVec(const Vec3& v, const char* sep, int decimals = 3) {
  return formatDouble(v[0], decimals) + sep + formatDouble(v[1], decimals) + sep + formatDouble(v[2], decimals);
}

json vecJson(const Vec3& v) { return json::array({v[0], v[1], v[2]}); }

json geometryJson(const Geometry& g) {
  json dir = json::array();
  for (int c = 0; c < 3; ++c) dir.push_back(vecJson(g.direction.column(c)));
  return {{"dimensions", {g.dims.x, g.dims.y, g.dims.z}},
          {"spacing_mm", vecJson(g.spacingMm)},
          {"origin_mm", vecJson(g.originMm)},
          {"direction_columns", dir},
          {"orientation", g.orientationCode()}};
}

json intensityJson(const IntensityModel& m) {
  return {{"unit", m.hounsfield() ? "HU" : "plain"},
          {"modality", m.modality},
          {"reason", m.reason},
          {"window", {m.valueOf(m.window[0]), m.valueOf(m.window[1])}},
          {"stored_window", {m.window[0], m.window[1]}},
          {"slope", m.slope},
          {"intercept", m.intercept}};
}

void printIntensity(const IntensityModel& m) {
  terminalPrintf("intensity:   %s (%s)\n", m.hounsfield() ? "Hounsfield units" : "plain intensities", m.reason.c_str());
  terminalPrintf("window:      %s … %s %s%s\n", formatDouble(m.valueOf(m.window[0]), 1).c_str(),
              formatDouble(m.valueOf(m.window[1]), 1).c_str(), m.unitName(),
              m.hounsfield() ? " (density 0 … 1 of the WDT)" : " (0.5th … 99.5th percentile; density 0 … 1 of the WDT)");
  if (!m.attenuationLike())
    terminalPrintf("note:        %s intensities are not attenuation: density-weighted distances assume CT-like values\n",
                m.modality.c_str());
}

void printGeometry(const Geometry& g) {
  terminalPrintf("dimensions:  %s\n", g.dims.toString().c_str());
  terminalPrintf("spacing:     %s mm\n", formatVec(g.spacingMm, " x ").c_str());
  terminalPrintf("origin:      (%s) mm, LPS\n", formatVec(g.originMm, ", ").c_str());
  terminalPrintf("orientation: %s (axis directions in LPS: i (%s), j (%s), k (%s))\n", g.orientationCode().c_str(),
              formatVec(g.direction.column(0), ", ", 3).c_str(), formatVec(g.direction.column(1), ", ", 3).c_str(),
              formatVec(g.direction.column(2), ", ", 3).c_str());
}

int usageError(const std::string& command, const std::string& message) {
  return reportError(command + ": " + message, 2);
}

// --- datasets ---------------------------------------------------------------------------------

// One row of `datasets`. Imported datasets (registered by `import` in the database, db/) are
// listed by the database layer and appended to the built-in ones here once it exists.
struct DatasetListing {
  std::string id;
  std::string name;
  std::string detail;
};

std::vector<DatasetListing> builtinDatasets() {
  const PhantomOptions defaults;
  std::vector<DatasetListing> listing = {
      {"phantom", "Temporal-bone phantom (synthetic)",
       std::to_string(defaults.size) + "^3 over " + formatDouble(defaults.extentMm, 1) + " mm, " +
           std::to_string(phantomStructures().size()) + " structures; phantom:N for N^3 (N = 16 … 1024)"}};
  for (const KnownScan& scan : knownScans()) {
    const auto path = locateKnownScan(scan);
    listing.push_back({scan.name, scan.title,
                       path ? path->string() + " (" + scan.licence + ")"
                            : "not fetched: bash scripts/fetch-scans.sh, or apt-get install " + scan.debianPackage});
  }
  return listing;
}

const char* kDatasetsHelp =
    "usage: anatomy-tutor datasets [--json] [--db PATH]\n\n"
    "Lists the datasets that can be opened by name: the built-in phantom, the real scans that\n"
    "scripts/fetch-scans.sh fetches from Debian packages (skull: a head CT), and the datasets imported\n"
    "with `anatomy-tutor import` into the database (--db PATH, else the default database). Any\n"
    "supported file or folder can also be opened directly by its path.\n";

// --- structures -------------------------------------------------------------------------------

const char* kStructuresHelp =
    "usage: anatomy-tutor structures DATASET [--json]\n"
    "       anatomy-tutor structures DATASET --structure ID --system SYSTEM   (imported datasets)\n"
    "       anatomy-tutor structures --volume PATH --labels PATH [--names JSON] [--series UID] [--json]\n\n"
    "Lists a dataset's structures: label value, id, name, system and voxel count. --structure ID\n"
    "--system SYSTEM stores the browsing group of an imported dataset's structure (\"\" clears it).\n"
    "DATASET is a built-in name (phantom, phantom:N, skull) or a volume path (DICOM folder, .nii[.gz],\n"
    ".nrrd/.nhdr, .inv3); --labels gives a label map on any grid (resampled onto the volume), --names a\n"
    "JSON map { \"value\": \"name\" }, --series the DICOM series UID. Datasets from files also take\n"
    "(as do slice, wdt and render):\n";

// --- info -------------------------------------------------------------------------------------

const char* kInfoHelp =
    "usage: anatomy-tutor info FILE|DIR|SCAN|DATASET [--json] [--labels PATH] [--names JSON] [--series UID]\n"
    "                          [--intensity auto|hu|plain] [--modality CODE] [--skip-unreadable] [--nrrd-data DIR]\n\n"
    "Loads any supported input (DICOM series folder, DICOM SEG, NIfTI, NRRD, InVesalius .inv3) and\n"
    "prints its dimensions, spacing, origin, orientation, stored type, value range and loader notes.\n"
    "SCAN is a real scan fetched by scripts/fetch-scans.sh (skull). DATASET is a dataset imported into\n"
    "--db (`anatomy-tutor datasets`): its volume file as imported (checked against its checksum), read\n"
    "as the other commands read it (its values with the --intensity/--intercept/--slope given at\n"
    "import, printed), with its structures (a file or folder of that name wins).\n"
    "An image's intensity model: CT in Hounsfield units (DICOM Modality CT, or values down to air\n"
    "at -1000), or plain intensities (unsigned µCT exports, MR, ...) with a window from the\n"
    "histogram; --intensity forces one. A file is listed as a label map when it names segments or\n"
    "holds at most 512 integer values that are piecewise constant (90 % of neighbouring non-zero\n"
    "voxels equal), so a noisy uint8 µCT is an image. Label maps and --labels inputs also list each\n"
    "label with its name and voxel count; --names JSON ({ \"value\": \"name\" }) names them.\n"
    "Only regular files are read (FIFOs and devices are refused).\n";

bool isIntegerKind(ScalarKind k) { return k != ScalarKind::Float32 && k != ScalarKind::Float64; }

// The dataset imported into --db under `name`, if there is one (no database file: none).
Result<std::optional<db::DatasetRecord>> importedDatasetNamed(const cli::Args& args, const std::string& name) {
  auto database = db::openExistingDatabase(args.db());
  if (!database) return tl::unexpected(database.error());
  if (!*database) return std::optional<db::DatasetRecord>{};
  return db::findDataset(**database, name);
}

struct ValueSummary {
  double min = 0, max = 0;
  bool allInteger = true;
  std::map<long, std::size_t> counts;  // filled while there are at most kMaxLabels distinct values
  bool fewValues = true;
};
constexpr std::size_t kMaxLabels = 512;

ValueSummary summarise(const FloatVolume& image) {
  ValueSummary s;
  bool first = true;
  for (float v : image.voxels) {
    if (first || v < s.min) s.min = v;
    if (first || v > s.max) s.max = v;
    first = false;
    if (s.allInteger && v != std::floor(v)) s.allInteger = false;
    if (s.fewValues && s.allInteger) {
      ++s.counts[long(v)];
      if (s.counts.size() > kMaxLabels) s.fewValues = false;
    }
  }
  if (!s.allInteger || !s.fewValues) s.counts.clear();
  return s;
}

// --- slice ------------------------------------------------------------------------------------

const char* kSliceHelp =
    "usage: anatomy-tutor slice DATASET (--plane axial|coronal|sagittal | --axis x|y|z) --index N --out FILE.png\n"
    "                           [--window C,W] [--alpha A] [--volume PATH --labels PATH ...]\n\n"
    "Writes one slice as a grey PNG (window centre C and width W in the dataset's values: HU for CT,\n"
    "default 400,2000; plain intensities default to the window from their histogram) with\n"
    "each labelled structure overlaid in its colour at opacity A (default 0.5; 0 = no overlay).\n"
    "--axis picks the voxel axis the slice is perpendicular to (z: axial for LPS data) and --index\n"
    "the slice (0-based). Image columns follow the i axis (j for --axis x); rows follow j for axial\n"
    "slices and run from the top (highest k) down otherwise.\n"
    "--plane instead shows the slice in patient orientation, whatever the file's voxel order, in the\n"
    "radiological convention: the patient's left on the image's right (axial, coronal), anterior up\n"
    "(axial) or superior up (coronal, sagittal; sagittal has anterior on the left); --index then\n"
    "counts along the voxel axis that crosses the plane. The edge letters (L R A P S I) are printed.\n"
    "Pixels are square in millimetres, so the picture has the anatomy's proportions: a voxel longer\n"
    "along the columns or the rows (3.2 x 1.5 mm) spans that many more pixels (printed: their size).\n";

}  // namespace

int runDatasets(const Argv& argv) {
  auto args = cli::Args::parse(argv, {}, {"json"});
  if (!args) return usageError("datasets", args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s", kDatasetsHelp);
    return 0;
  }
  if (!args->positional().empty()) return usageError("datasets", "unexpected argument '" + args->positional()[0] + "'");
  std::vector<DatasetListing> rows = builtinDatasets();
  std::vector<bool> builtin(rows.size(), true);
  auto database = db::openExistingDatabase(args->db());
  if (!database) return reportError("datasets: " + database.error().message);
  auto imported = *database ? db::listDatasets(**database) : Result<std::vector<db::DatasetRecord>>(std::vector<db::DatasetRecord>{});
  if (!imported) return reportError("datasets: " + imported.error().message);
  for (const db::DatasetRecord& r : *imported) {
    rows.push_back({r.name, r.species + " dataset from " + r.volumePath,
                    r.geometry.dims.toString() + ", " + std::to_string(r.structureCount) + " structures, imported " +
                        r.createdAt});
    builtin.push_back(false);
  }
  if (args->has("json")) {
    json list = json::array();
    for (std::size_t i = 0; i < rows.size(); ++i)
      list.push_back({{"id", rows[i].id}, {"name", rows[i].name}, {"detail", rows[i].detail}, {"builtin", bool(builtin[i])}});
    std::printf("%s\n", json{{"datasets", list}}.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace).c_str());
    return 0;
  }
  for (const auto& r : rows)
    terminalPrintf("%-10s %s — %s\n", rowCell(r.id).c_str(), rowCell(r.name).c_str(), rowCell(r.detail).c_str());
  if (imported->empty())
    terminalPrintf("(no imported datasets yet: `anatomy-tutor import` adds them; any supported file or folder can\n"
                " also be opened by its path)\n");
  return 0;
}

int runStructures(const Argv& argv) {
  auto args = cli::Args::parse(argv, with(kDatasetOptions, {"structure", "system"}), withDatasetFlags({"json"}));
  if (!args) return usageError("structures", args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s%s", kStructuresHelp, kDatasetOptionsHelp);
    return 0;
  }
  if (args->value("structure") || args->value("system")) {
    const auto id = args->value("structure"), system = args->value("system");
    if (!id || !system) return usageError("structures", "--structure ID and --system SYSTEM go together");
    if (args->positional().size() != 1) return usageError("structures", "--system needs one imported DATASET name");
    auto database = db::openDatabase(args->db());
    if (!database) return reportError("structures: " + database.error().message);
    if (auto ok = db::setStructureSystem(*database, args->positional()[0], *id, *system); !ok)
      return reportError("structures: " + ok.error().message);
    terminalPrintf("%s: structure '%s' is now in system '%s'\n", args->positional()[0].c_str(), id->c_str(), system->c_str());
    return 0;
  }
  auto ds = openDatasetArg(*args);
  if (!ds) return reportError("structures: " + ds.error().message);
  const std::vector<std::size_t> counts = labelHistogram(ds->labels);
  if (args->has("json")) {
    json list = json::array();
    for (const Structure& s : ds->structures)
      list.push_back({{"label", s.label},
                      {"id", s.id},
                      {"name", s.displayName},
                      {"system", s.system},
                      {"voxels", counts[s.label]},
                      {"colour", {s.colour[0], s.colour[1], s.colour[2]}}});
    std::printf("%s\n", json{{"dataset", ds->id}, {"name", ds->displayName}, {"structures", list}}.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace).c_str());
    return 0;
  }
  terminalPrintf("%s — %s (%s)\n", ds->id.c_str(), ds->displayName.c_str(), ds->volume.dims().toString().c_str());
  terminalPrintf("%5s  %-30s %-30s %-13s %10s\n", "label", "id", "name", "system", "voxels");
  for (const Structure& s : ds->structures)
    terminalPrintf("%5u  %-30s %-30s %-13s %10zu\n", unsigned(s.label), s.id.c_str(), s.displayName.c_str(),
                s.system.c_str(), counts[s.label]);
  return 0;
}

int runInfo(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"labels", "names", "series", "intensity", "nrrd-data", "modality"},
                               withDatasetFlags({"json"}));
  if (!args) return usageError("info", args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s%s", kInfoHelp, kDatasetOptionsHelp);
    return 0;
  }
  const auto& pos = args->positional();
  if (pos.empty()) return usageError("info", "missing FILE or DIR (see --help)");
  if (pos.size() > 1) return usageError("info", "unexpected argument '" + pos[1] + "' (one FILE or DIR only)");
  std::string path = pos[0];
  ImageLoadOptions options;
  options.dicomSeriesUid = args->valueOr("series", "");
  options.skipUnreadableFiles = args->has("skip-unreadable");
  if (auto folder = args->value("nrrd-data")) options.dataFolder = fs::absolute(*folder).string();
  // A scan's name wins over a file of that name, as built-in names do everywhere (./skull is the file).
  std::optional<db::DatasetRecord> imported;
  std::error_code ec;
  if (const KnownScan* scan = findKnownScan(path)) {
    // Described as every command reads it, so the options that read a file another way are refused.
    for (const char* option : {"series", "intensity", "skip-unreadable", "nrrd-data", "modality"})
      if (args->has(option))
        return usageError("info", std::string("--") + option + " applies to volume files and folders, not to the fetched scan '" +
                                      scan->name + "' (it is read as fetched)");
    auto file = knownScanFile(*scan);
    if (!file) return reportError("info: " + file.error().message);
    path = file->string();
  } else if (!fs::exists(path, ec)) {
    auto found = importedDatasetNamed(*args, path);
    if (!found) return reportError("info: " + found.error().message);
    if (!*found)
      return reportError("info: " + path + ": no such file or folder, scan or imported dataset (`anatomy-tutor datasets` lists "
                         "the datasets)");
    imported = std::move(*found);
  }
  std::optional<Dataset> asImported;  // the imported dataset as the other commands read it
  if (imported) {
    for (const char* option : {"labels", "names", "series", "intensity", "skip-unreadable", "nrrd-data", "modality"})
      if (args->has(option))
        return usageError("info", std::string("--") + option + " applies to files, not to imported '" + imported->name +
                                      "' (its files are read as at import)");
    // Opening it checks its files against their checksums; the file is then described as read.
    auto dataset = openDatasetArg(*args);
    if (!dataset) return reportError("info: " + dataset.error().message);
    asImported = std::move(*dataset);
    const DatasetFiles files = db::datasetFiles(*imported);
    path = files.volumePath;
    options.dicomSeriesUid = files.dicomSeriesUid;
    options.skipUnreadableFiles = files.skipUnreadableFiles;
    options.dataFolder = files.dataFolder;
  }
  auto loaded = loadImageFile(path, options);
  if (!loaded) return reportError("info: " + loaded.error().message);
  // --modality names what a file does not record (as for every command: DatasetFiles::modality).
  std::string givenModality;
  if (auto text = args->value("modality")) {
    auto code = parseModalityCode(*text);
    if (!code) return usageError("info", "--" + code.error().message);
    givenModality = *code;
    if (auto ok = takeGivenModality(*loaded, givenModality, path); !ok) return reportError("info: " + ok.error().message);
  }
  const Geometry& g = loaded->image.geometry;
  ValueSummary values = summarise(loaded->image);
  // A file given alone is a label map when it names its segments or passes the documented test
  // (volume/intensity.h: few integer values, piecewise constant); a µCT's uint8 data is not one.
  // An imported dataset's volume is its image.
  const bool labelMap = !asImported && (!loaded->segments.empty() || (isIntegerKind(loaded->storedKind) && values.fewValues &&
                                                                       looksLikeLabelMap(loaded->image)));
  auto intensityChoice = parseIntensityChoice(args->valueOr("intensity", "auto"));
  if (!intensityChoice) return usageError("info", "--intensity: " + intensityChoice.error().message);
  std::optional<IntensityModel> intensity;
  if (asImported) {
    // Its values as read (after the import's rescale), not as the file stores them.
    intensity = asImported->intensity;
    values = ValueSummary{};
    bool first = true;
    for (auto v : asImported->volume.voxels) {
      const double value = asImported->intensity.valueOf(v);
      if (first || value < values.min) values.min = value;
      if (first || value > values.max) values.max = value;
      first = false;
    }
  } else if (!labelMap) {
    auto stored = toStoredVolume(*loaded, path, *intensityChoice);
    if (!stored) return reportError("info: " + stored.error().message);
    intensity = std::move(stored->intensity);
  }
  if (args->has("names") && !args->has("labels") && !labelMap)
    return usageError("info", "--names applies to a label map, or to the label map given with --labels");

  // Labels with names and voxel counts: from the file itself when it is a label map, from
  // --labels (resampled onto this image's grid) otherwise.
  struct LabelRow {
    long value;
    std::string id;    // the structure id (files that only name labels: the name as written)
    std::string name;  // display name
    std::size_t voxels;
  };
  std::vector<LabelRow> labels;
  if (asImported) {
    const std::vector<std::size_t> counts = labelHistogram(asImported->labels);
    for (const Structure& s : asImported->structures)
      labels.push_back({long(s.label), s.id, s.displayName, counts[s.label]});
  } else if (args->has("labels")) {
    DatasetFiles files;
    files.volumePath = path;
    files.labelsPath = *args->value("labels");
    files.namesPath = args->valueOr("names", "");
    files.dicomSeriesUid = options.dicomSeriesUid;
    files.intensity = *intensityChoice;
    files.id = fs::path(path).filename().string();
    files.skipUnreadableFiles = options.skipUnreadableFiles;
    files.dataFolder = options.dataFolder;
    files.modality = givenModality;
    auto ds = openDatasetFiles(files);
    if (!ds) return reportError("info: " + ds.error().message);
    const std::vector<std::size_t> counts = labelHistogram(ds->labels);
    for (const Structure& s : ds->structures)
      labels.push_back({long(s.label), s.id, s.displayName, counts[s.label]});
  } else if (labelMap) {
    std::map<long, std::string> names;
    for (const SegmentInfo& s : loaded->segments) names[long(s.label)] = s.name;
    if (auto namesPath = args->value("names")) {
      auto fromJson = loadLabelNames(*namesPath);
      if (!fromJson) return reportError("info: " + fromJson.error().message);
      for (const auto& [value, name] : *fromJson) names[long(value)] = name;
    }
    for (const auto& [value, count] : values.counts) {
      if (value == 0) continue;
      auto it = names.find(value);
      const std::string name = it != names.end() ? printableText(it->second, 120) : "label_" + std::to_string(value);
      labels.push_back({value, name, name, count});
    }
  }

  if (args->has("json")) {
    json out = geometryJson(g);
    out["path"] = path;
    if (imported)
      out["dataset"] = {{"name", imported->name},
                        {"imported", imported->createdAt},
                        {"species", imported->species},
                        {"load_options", str::trim(db::loadOptionArguments(*imported))}};
    out["kind"] = labelMap ? "label map" : "image";
    if (intensity) out["intensity"] = intensityJson(*intensity);
    out["stored_type"] = toString(loaded->storedKind);
    out["value_range"] = {values.min, values.max};
    json notes = json::array();
    for (const std::string& note : loaded->notes) notes.push_back(printableText(note, 400));
    out["notes"] = notes;
    json list = json::array();
    for (const auto& l : labels)
      list.push_back({{"label", l.value}, {"id", l.id}, {"name", l.name}, {"voxels", l.voxels}});
    out["labels"] = list;
    std::printf("%s\n", out.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace).c_str());
    return 0;
  }
  if (imported) {
    const std::string readWith = str::trim(db::loadOptionArguments(*imported));
    terminalPrintf("dataset:     %s (%s, imported %s; values read %s)\n", imported->name.c_str(), imported->species.c_str(),
                   imported->createdAt.c_str(), readWith.empty() ? "as stored" : ("with " + readWith).c_str());
  }
  terminalPrintf("path:        %s\n", path.c_str());
  terminalPrintf("kind:        %s\n", labelMap ? "label map" : "image");
  if (intensity) printIntensity(*intensity);
  printGeometry(g);
  terminalPrintf("stored type: %s\n", toString(loaded->storedKind));
  terminalPrintf("%s %s … %s\n", intensity && intensity->hounsfield() ? "HU range:   " : "value range:", formatDouble(values.min, 1).c_str(),
              formatDouble(values.max, 1).c_str());
  for (const std::string& note : loaded->notes) terminalPrintf("note:        %s\n", printableText(note, 400).c_str());
  if (!labels.empty()) {
    terminalPrintf("labels:      %zu\n", labels.size());
    for (const auto& l : labels) {
      if (l.id == l.name)
        terminalPrintf("  %5ld  %-64s %10zu voxels\n", l.value, l.name.c_str(), l.voxels);
      else
        terminalPrintf("  %5ld  %-31s  %-31s %10zu voxels\n", l.value, l.id.c_str(), l.name.c_str(), l.voxels);
    }
  }
  return 0;
}

int runSlice(const Argv& argv) {
  auto args = cli::Args::parse(argv, with(kDatasetOptions, {"axis", "plane", "index", "out", "window", "alpha"}), withDatasetFlags({}));
  if (!args) return usageError("slice", args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s", kSliceHelp);
    return 0;
  }
  const auto axisText = args->value("axis"), planeText = args->value("plane");
  if (!axisText && !planeText) return usageError("slice", "missing --plane axial|coronal|sagittal or --axis x|y|z");
  if (axisText && planeText) return usageError("slice", "give --plane or --axis, not both");
  if (axisText && *axisText != "x" && *axisText != "y" && *axisText != "z")
    return usageError("slice", "--axis must be x, y or z, not '" + *axisText + "'");
  std::optional<PatientPlane> plane;
  for (PatientPlane p : {PatientPlane::Sagittal, PatientPlane::Coronal, PatientPlane::Axial})
    if (planeText && *planeText == planeName(p)) plane = p;
  if (planeText && !plane) return usageError("slice", "--plane must be axial, coronal or sagittal, not '" + *planeText + "'");
  if (!args->value("index")) return usageError("slice", "missing --index N");
  auto index = args->integer("index", 0);
  if (!index) return usageError("slice", index.error().message);
  const auto out = args->value("out");
  if (!out || out->empty()) return usageError("slice", "missing --out FILE.png");
  double centre = 400, width = 2000;
  const auto windowText = args->value("window");
  if (auto w = windowText) {
    const auto comma = w->find(',');
    char* end = nullptr;
    bool ok = comma != std::string::npos;
    if (ok) {
      const std::string c = w->substr(0, comma), wd = w->substr(comma + 1);
      centre = std::strtod(c.c_str(), &end);
      ok = !c.empty() && *end == '\0';
      width = std::strtod(wd.c_str(), &end);
      ok = ok && !wd.empty() && *end == '\0' && std::isfinite(centre) && std::isfinite(width) && width > 0;
    }
    if (!ok) return usageError("slice", "--window must be CENTRE,WIDTH with WIDTH > 0 (e.g. 400,2000), not '" + *w + "'");
  }
  auto alpha = args->number("alpha", 0.5);
  if (!alpha) return usageError("slice", alpha.error().message);
  if (*alpha < 0 || *alpha > 1) return usageError("slice", "--alpha must lie in 0 … 1");

  auto ds = openDatasetArg(*args);
  if (!ds) return reportError("slice: " + ds.error().message);
  const IntensityModel& intensity = ds->intensity;
  if (!windowText && !intensity.hounsfield()) {  // plain intensities: the dataset's window
    const double lo = intensity.valueOf(intensity.window[0]), hi = intensity.valueOf(intensity.window[1]);
    centre = 0.5 * (lo + hi);
    width = hi - lo;
  }
  const Mat3& direction = ds->volume.geometry.direction;
  const SliceLayout layout = plane ? patientSliceLayout(direction, *plane) : voxelSliceLayout((*axisText)[0] - 'x', direction);
  const int axis = layout.sliceAxis;
  const std::string across = plane ? std::string(planeName(*plane)) + " (voxel axis " + char('x' + axis) + ")" : "axis " + *axisText;
  const Dims& d = ds->volume.dims();
  const int extent[3] = {d.x, d.y, d.z};
  if (*index < 0 || *index >= extent[axis])
    return reportError("slice: --index " + std::to_string(*index) + " is outside 0 … " +
                       std::to_string(extent[axis] - 1) + " for " + across + " of " + ds->id + " (" +
                       d.toString() + ")");

  SliceRequest request;
  request.layout = layout;
  request.index = *index;
  // The window is in the dataset's values; renderSlice maps stored ones.
  request.windowCentreHu = (centre - intensity.intercept) / intensity.slope;
  request.windowWidthHu = width / intensity.slope;
  request.labelAlpha = *alpha;
  auto voxels = renderSlice(ds->volume, &ds->labels, ds->structures, request);
  if (!voxels) return reportError("slice: " + voxels.error().message);
  // Square pixels: the picture keeps the anatomy's proportions whatever the voxels' shape.
  const auto& spacing = ds->volume.geometry.spacingMm;
  double pixelMm = 0;
  const RgbImage image = withSquarePixels(
      *voxels, {spacing[std::size_t(layout.columnAxis)], spacing[std::size_t(layout.rowAxis)]}, &pixelMm);
  if (auto st = writePng(*out, image); !st) return reportError("slice: " + st.error().message);
  terminalPrintf("wrote %s (%dx%d, pixels of %s mm, %s index %d of %s, window %s,%s; %s)\n", out->c_str(), image.width,
                 image.height, formatDouble(pixelMm, 3).c_str(), across.c_str(), *index, ds->id.c_str(),
                 formatDouble(centre, 0).c_str(), formatDouble(width, 0).c_str(), layout.edgeLetters().c_str());
  return 0;
}

}  // namespace at::app
