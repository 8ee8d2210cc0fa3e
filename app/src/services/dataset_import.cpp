#include "dataset_import.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>

#include "core/safe_name.h"
#include "db/checksum.h"
#include "volume/dataset_source.h"
#include "volume/structure_forms.h"

namespace at::app {

namespace {

// `what` names the input in messages ("volume", "labels", "names").
Result<std::string> absolutePath(const std::string& what, const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) return fail(ErrorKind::NotFound, what + " " + path + ": no such file or folder");
  auto absolute = std::filesystem::weakly_canonical(std::filesystem::absolute(path), ec);
  if (ec) return fail(what + " " + path + ": " + ec.message());
  return absolute.string();
}

}  // namespace

const char* toString(ImportStage stage) {
  switch (stage) {
    case ImportStage::Checking: return "checking";
    case ImportStage::LoadingVolume: return "loading volume";
    case ImportStage::LoadingLabels: return "loading labels";
    case ImportStage::CheckingAlignment: return "checking alignment";
    case ImportStage::Checksums: return "checksums";
    case ImportStage::Storing: return "storing";
  }
  return "?";
}

Result<ImportedDataset> importDataset(db::Database& database, const ImportRequest& request, const ImportControl& control) {
  const auto cancelled = [&] { return control.cancel && control.cancel->load(); };
  const auto stage = [&](ImportStage s) {
    if (control.progress) control.progress(s, 0, 0);
  };
  stage(ImportStage::Checking);
  if (request.volumePath.empty()) return fail("a volume (DICOM folder, .nii, .nii.gz, .nrrd, .nhdr or .inv3) is required");
  if (request.name.empty()) return fail("a dataset name is required");
  if (isBuiltinDatasetName(request.name)) return fail("'" + request.name + "' is the built-in dataset's name; choose another name");
  // Dataset names become folder names (a course export, the data folder, the segmentations).
  if (auto ok = checkSafeName("dataset name", request.name); !ok) return tl::unexpected(ok.error());
  if (!isValidSpecies(request.species))
    return fail("species '" + request.species + "': use lower-case letters, '-' and '_' (human, dog, …)");

  ImportedDataset out;
  db::DatasetRecord& record = out.record;
  record.name = request.name;
  record.species = request.species;
  auto volumePath = absolutePath("volume", request.volumePath);
  if (!volumePath) return tl::unexpected(volumePath.error());
  record.volumePath = *volumePath;
  if (!request.labelsPath.empty()) {
    auto p = absolutePath("labels", request.labelsPath);
    if (!p) return tl::unexpected(p.error());
    record.labelsPath = *p;
  }
  if (!request.namesPath.empty()) {
    auto p = absolutePath("names", request.namesPath);
    if (!p) return tl::unexpected(p.error());
    record.namesPath = *p;
  }
  record.skipUnreadableFiles = request.skipUnreadableFiles;
  if (!request.dataFolder.empty()) {
    auto p = absolutePath("NRRD data folder", request.dataFolder);
    if (!p) return tl::unexpected(p.error());
    record.dataFolder = *p;
  }

  record.intensity = request.intensity;
  record.intercept = request.intercept;
  record.slope = request.slope;
  if (auto ok = checkRescale(record.intercept.value_or(0), record.slope.value_or(1)); !ok) return tl::unexpected(ok.error());
  if (!request.modality.empty()) {
    auto modality = parseModalityCode(request.modality);
    if (!modality) return fail("--" + modality.error().message);
    record.modality = *modality;
  }

  // Fail fast on a taken name, before the (possibly long) load.
  auto existing = db::findDataset(database, record.name);
  if (!existing) return tl::unexpected(existing.error());
  if (*existing && !request.replace)
    return fail(ErrorKind::Conflict, "a dataset named '" + record.name + "' is already imported; choose another name");
  if (cancelled()) return fail(ErrorKind::Cancelled, kImportCancelled);

  DatasetLoadControl load;
  load.cancel = control.cancel;
  if (control.progress)
    load.progress = [&](DatasetLoadPart part, std::size_t done, std::size_t total) {
      // Resampling and names belong to the labels stage.
      const ImportStage s = part == DatasetLoadPart::Volume ? ImportStage::LoadingVolume : ImportStage::LoadingLabels;
      if (part == DatasetLoadPart::Volume || part == DatasetLoadPart::Labels || done == 0) control.progress(s, done, total);
    };
  auto dataset = openDatasetFiles(db::datasetFiles(record), load);
  if (cancelled()) return fail(ErrorKind::Cancelled, kImportCancelled);
  if (!dataset) return tl::unexpected(dataset.error());

  // Alignment: every structure must keep voxels on the volume's grid.
  stage(ImportStage::CheckingAlignment);
  std::map<std::uint16_t, std::size_t> voxels;
  for (std::uint16_t v : dataset->labels.voxels)
    if (v != 0) ++voxels[v];
  if (!record.labelsPath.empty() && voxels.empty())
    return fail(record.labelsPath + ": no labelled voxel falls inside the volume " + record.volumePath +
                " (the two do not overlap in patient space)");
  for (const Structure& s : dataset->structures)
    if (voxels.count(s.label) == 0) out.emptyStructures.push_back(s.id);
  if (cancelled()) return fail(ErrorKind::Cancelled, kImportCancelled);

  stage(ImportStage::Checksums);
  auto volumeSum = db::checksumPath(record.volumePath, record.dataFolder);
  if (!volumeSum) return tl::unexpected(volumeSum.error());
  record.volumeChecksum = *volumeSum;
  if (!record.labelsPath.empty()) {
    if (cancelled()) return fail(ErrorKind::Cancelled, kImportCancelled);
    auto labelsSum = db::checksumPath(record.labelsPath, record.dataFolder);
    if (!labelsSum) return tl::unexpected(labelsSum.error());
    record.labelsChecksum = *labelsSum;
  }
  record.geometry = dataset->volume.geometry;
  record.orientation = record.geometry.orientationCode();
  if (cancelled()) return fail(ErrorKind::Cancelled, kImportCancelled);

  stage(ImportStage::Storing);
  auto id = db::registerDataset(database, record, dataset->structures, request.replace);
  if (!id) return tl::unexpected(id.error());
  record.id = *id;
  record.structureCount = int(dataset->structures.size());
  dataset->id = record.name;
  dataset->displayName = record.name;
  dataset->species = record.species;
  out.dataset = std::move(*dataset);
  return out;
}

}  // namespace at::app
