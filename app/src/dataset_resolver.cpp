#include "dataset_resolver.h"

#include <filesystem>

#include "db/dataset_store.h"
#include "volume/dataset_source.h"

namespace at::app {

namespace fs = std::filesystem;

std::set<std::string> withDatasetOptions(std::set<std::string> commandOptions) {
  commandOptions.insert({"labels", "names", "series", "nrrd-data", "db"});
  return commandOptions;
}

std::set<std::string> withDatasetFlags(std::set<std::string> commandFlags) {
  commandFlags.insert("skip-unreadable");
  return commandFlags;
}

DatasetRequest datasetRequestFrom(const cli::Args& args, const std::string& name) {
  DatasetRequest request;
  request.name = name;
  request.labelsPath = args.valueOr("labels", "");
  request.namesPath = args.valueOr("names", "");
  request.seriesUid = args.valueOr("series", "");
  request.dbPath = args.value("db");
  request.skipUnreadableFiles = args.has("skip-unreadable");
  if (auto folder = args.value("nrrd-data")) request.dataFolder = fs::absolute(*folder).string();
  return request;
}

Result<Dataset> openNamedDataset(const DatasetRequest& request) {
  const bool fileOptions = !request.labelsPath.empty() || !request.namesPath.empty() || !request.seriesUid.empty() ||
                           request.skipUnreadableFiles || !request.dataFolder.empty();
  if (isBuiltinDatasetName(request.name)) {
    if (fileOptions)
      return fail("--labels, --names, --series, --skip-unreadable and --nrrd-data apply to datasets from files, not to '" +
                  request.name + "'");
    return openBuiltinDataset(request.name);
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
    files.skipUnreadableFiles = request.skipUnreadableFiles;
    files.dataFolder = request.dataFolder;
    return openDatasetFiles(files);
  }
  auto imported = db::findImportedDataset(request.dbPath, request.name);
  if (!imported) return tl::unexpected(imported.error());
  if (*imported) {
    if (fileOptions)
      return fail("--labels, --names, --series, --skip-unreadable and --nrrd-data apply to datasets from files, not to "
                  "imported '" + request.name + "' (its files are read as at import)");
    return openDatasetFiles(**imported);
  }
  std::string known;
  if (auto all = db::listImportedDatasets(request.dbPath))
    for (const auto& record : *all) known += (known.empty() ? "" : ", ") + record.name;
  return fail(ErrorKind::NotFound, "unknown dataset '" + request.name + "': not built in (phantom, phantom:N), not imported" +
              (known.empty() ? std::string() : " (imported: " + known + ")") + ", and no such file or folder");
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
