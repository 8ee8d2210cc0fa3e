#include "learning_support.h"

#include <cstdlib>
#include <filesystem>

#include "db/course_store.h"
#include "db/dataset_store.h"
#include "volume/dataset_source.h"
#include "volume/phantom.h"
#include "wdt/wdt.h"

namespace at::app {

std::string courseDirectory() {
  if (const char* dir = std::getenv("AT_DATA_DIR"); dir && *dir) return (std::filesystem::path(dir) / "courses").string();
  return (std::filesystem::path(AT_SOURCE_DIR) / "data" / "courses").string();
}

Result<db::Database> openLearningDatabase(const std::optional<std::string>& dbPath, bool readOnly) {
  db::OpenOptions options;
  options.readOnlyIfNotWritable = readOnly;
  auto database = db::openDatabase(dbPath, options);
  if (!database) return tl::unexpected(database.error());
  if (database->readOnly()) return std::move(*database);
  auto seeded = db::seedCourses(*database, courseDirectory());
  if (!seeded) return tl::unexpected(withContext("seeding the default course", seeded.error()));
  return std::move(*database);
}

db::BuiltinStructures builtinStructures() {
  return [](const std::string& datasetId) -> std::optional<std::vector<Structure>> {
    if (!isBuiltinDatasetName(datasetId)) return std::nullopt;
    return phantomStructures();
  };
}

Result<Dataset> loadCourseDataset(db::Database& database, const std::string& datasetId) {
  if (isBuiltinDatasetName(datasetId)) return openBuiltinDataset(datasetId);
  auto record = db::findDataset(database, datasetId);
  if (!record) return tl::unexpected(record.error());
  if (!*record) return fail("unknown dataset '" + datasetId + "' (import it with `anatomy-tutor import`)");
  auto files = db::verifiedDatasetFiles(**record);
  if (!files) return tl::unexpected(files.error());
  auto dataset = openDatasetFiles(*files);
  if (!dataset) return tl::unexpected(withContext("dataset '" + datasetId + "'", dataset.error()));
  // Imported structures keep the names and descriptions stored at import time.
  auto stored = db::datasetStructures(database, (*record)->id);
  if (!stored) return tl::unexpected(stored.error());
  dataset->structures = std::move(*stored);
  dataset->species = (*record)->species;
  return dataset;
}

quiz::DistanceFieldFunction wdtDistanceField(const Dataset& dataset) {
  return [&dataset](const Mask& seeds) -> Result<FloatVolume> {
    WdtParams params;
    params.converge = true;
    params.downsample = 2;
    auto result = computeWdt(dataset.volume, seeds, params);
    if (!result) return tl::unexpected(result.error());
    if (result->field.downsample == 1) return std::move(result->field.distances);
    return upsampleField(result->field, dataset.labels.geometry);
  };
}

LazyKeyComputer::LazyKeyComputer(std::vector<Structure> structures, Loader loader)
    : structures_(std::move(structures)), loader_(std::move(loader)) {}

bool LazyKeyComputer::hasStructure(const std::string& structureId) const {
  for (const Structure& s : structures_)
    if (s.id == structureId) return true;
  return false;
}

Result<quiz::KeyComputer*> LazyKeyComputer::loaded() {
  if (!keys_) {
    auto dataset = loader_();
    if (!dataset) return tl::unexpected(dataset.error());
    dataset_ = std::make_unique<Dataset>(std::move(*dataset));
    keys_ = std::make_unique<quiz::DatasetKeyComputer>(*dataset_, wdtDistanceField(*dataset_));
  }
  return keys_.get();
}

Result<quiz::StructureDistances> LazyKeyComputer::distancesFrom(const std::string& structureId) {
  auto keys = loaded();
  if (!keys) return tl::unexpected(keys.error());
  return (*keys)->distancesFrom(structureId);
}

Result<Vec3> LazyKeyComputer::centroidMm(const std::string& structureId) {
  auto keys = loaded();
  if (!keys) return tl::unexpected(keys.error());
  return (*keys)->centroidMm(structureId);
}

Result<std::vector<std::string>> LazyKeyComputer::structuresAlong(const Vec3& entryMm, const Vec3& targetMm) {
  auto keys = loaded();
  if (!keys) return tl::unexpected(keys.error());
  return (*keys)->structuresAlong(entryMm, targetMm);
}

}  // namespace at::app
