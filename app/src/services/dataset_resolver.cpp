#include "dataset_resolver.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>

#include "core/strings.h"
#include "db/dataset_store.h"
#include "scan_catalogue.h"
#include "volume/dataset_source.h"
#include "volume/known_scans.h"

namespace at::app {

namespace fs = std::filesystem;

namespace {

Result<double> numberOption(const std::string& option, const std::string& text) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(value))
    return fail("--" + option + ": '" + text + "' is not a number");
  return value;
}

// --intercept/--slope as numbers (applied by openDatasetFiles: volume/intensity.h, applyRescale).
Status readRescale(const DatasetRequest& request, DatasetFiles& files) {
  if (!request.intercept.empty()) {
    auto v = numberOption("intercept", request.intercept);
    if (!v) return tl::unexpected(v.error());
    files.intercept = *v;
  }
  if (!request.slope.empty()) {
    auto v = numberOption("slope", request.slope);
    if (!v) return tl::unexpected(v.error());
    if (*v == 0) return fail("--slope: must not be 0");
    files.slope = *v;
  }
  return {};
}

}  // namespace

Result<Dataset> openNamedDataset(const DatasetRequest& request) {
  const bool fileOptions = !request.labelsPath.empty() || !request.namesPath.empty() || !request.seriesUid.empty() ||
                           !request.intensity.empty() || request.skipUnreadableFiles || !request.dataFolder.empty() ||
                           !request.intercept.empty() || !request.slope.empty() || !request.modality.empty();
  if (isBuiltinDatasetName(request.name)) {
    if (fileOptions)
      return fail("--labels, --names, --series, --intensity, --skip-unreadable, --nrrd-data, --intercept, --slope and "
                  "--modality apply to datasets from files, not to '" + request.name + "'");
    return openBuiltinDataset(request.name);
  }
  if (const KnownScan* scan = findKnownScan(request.name)) {
    // A fetched scan is read one way, the way its entry says; only its labels may be another file.
    if (!request.seriesUid.empty() || request.skipUnreadableFiles || !request.dataFolder.empty() || !request.modality.empty() ||
        !request.intensity.empty() || !request.intercept.empty() || !request.slope.empty())
      return fail("--series, --intensity, --skip-unreadable, --nrrd-data, --intercept, --slope and --modality apply to "
                  "volume files and folders, not to the fetched scan '" + request.name + "' (it is read as fetched)");
    if (!request.namesPath.empty() && request.labelsPath.empty()) return fail("--names needs --labels PATH");
    auto dataset = openKnownScan(*scan, {request.labelsPath, request.namesPath});
    if (!dataset) return dataset;
    // The labels scripts/label-scans.sh grew: their structures described by the shipped catalogue.
    if (request.labelsPath.empty() && !dataset->structures.empty()) {
      auto catalogue = loadStructureCatalogue(catalogueFileFor(scan->name));
      if (!catalogue) return tl::unexpected(catalogue.error());
      applyCatalogue(*dataset, *catalogue);
    }
    return dataset;
  }
  std::error_code ec;
  if (fs::exists(request.name, ec)) {
    if (!request.namesPath.empty() && request.labelsPath.empty()) return fail("--names needs --labels PATH");
    DatasetFiles files;
    files.volumePath = request.name;
    files.labelsPath = request.labelsPath;
    files.namesPath = request.namesPath;
    files.dicomSeriesUid = request.seriesUid;
    files.id = fs::path(request.name).filename().string();
    if (!request.intensity.empty()) {
      auto choice = parseIntensityChoice(request.intensity);
      if (!choice) return fail("--intensity: " + choice.error().message);
      files.intensity = *choice;
    }
    files.skipUnreadableFiles = request.skipUnreadableFiles;
    files.dataFolder = request.dataFolder;
    if (auto ok = readRescale(request, files); !ok) return tl::unexpected(ok.error());
    if (!request.modality.empty()) {
      auto modality = parseModalityCode(request.modality);
      if (!modality) return fail("--" + modality.error().message);
      files.modality = *modality;
    }
    return openDatasetFiles(files);
  }
  std::optional<db::Connection> opened;
  db::Database* database = request.database;
  if (!database) {
    auto existing = db::openExistingDatabase(request.dbPath);
    if (!existing) return tl::unexpected(existing.error());
    if (*existing) database = &opened.emplace(std::move(**existing)).get();
  }
  std::vector<std::string> known;
  if (database) {
    auto record = db::findDataset(*database, request.name);
    if (!record) return tl::unexpected(record.error());
    if (*record) {
      if (fileOptions)
        return fail("--labels, --names, --series, --intensity, --skip-unreadable, --nrrd-data, --intercept, --slope "
                    "and --modality apply to datasets from files, not to imported '" + request.name +
                    "' (its files are read as at import)");
      // The files must be those imported: a file changed since is refused (checksums).
      auto files = db::verifiedDatasetFiles(**record);
      if (!files) return tl::unexpected(files.error());
      auto dataset = openDatasetFiles(*files);
      if (!dataset) return tl::unexpected(dataset.error());
      // Imported structures keep the names and descriptions stored at import time.
      auto stored = db::datasetStructures(*database, (*record)->id);
      if (!stored) return tl::unexpected(stored.error());
      dataset->structures = std::move(*stored);
      dataset->species = (*record)->species;
      return dataset;
    }
    if (auto all = db::listDatasets(*database))
      for (const auto& r : *all) known.push_back(r.name);
  }
  return fail(ErrorKind::NotFound, "unknown dataset '" + request.name + "': not built in (phantom, phantom:N, skull), not imported" +
                                       (known.empty() ? std::string() : " (imported: " + str::join(known, ", ") + ")") +
                                       ", and no such file or folder");
}

std::string unknownStructureMessage(const Dataset& dataset, const std::string& name) {
  if (dataset.structures.empty()) {
    return "dataset '" + dataset.id + "' has no labelled structures, so it has no '" + name +
           "' (a volume file or folder takes its label map with --labels FILE [--names NAMES.json], and "
           "`anatomy-tutor import --labels` registers a dataset with one)";
  }
  constexpr std::size_t kShown = 10;
  std::string ids;
  for (std::size_t i = 0; i < dataset.structures.size() && i < kShown; ++i) ids += (i ? ", " : "") + dataset.structures[i].id;
  if (dataset.structures.size() > kShown)
    ids += ", and " + std::to_string(dataset.structures.size() - kShown) + " more: anatomy-tutor structures lists them";
  return "dataset '" + dataset.id + "' has no structure '" + name + "' (it has: " + ids + ")";
}

}  // namespace at::app
