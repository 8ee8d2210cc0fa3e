// Imported datasets: where their files are (absolute paths + checksums), their geometry and
// species, and their structures. Never pixel data, never patient identifiers.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "db/connection.h"
#include "volume/dataset_source.h"
#include "volume/geometry.h"
#include "volume/structure.h"

namespace at::db {

struct DatasetRecord {
  std::int64_t id = 0;
  std::string name;                 // unique; what commands take as DATASET
  std::string species = "human";
  // Paths are absolute, or stored relative to the database file's folder (a course package's
  // dataset, kept in the database's data folder: the two move together) and read back absolute.
  std::string volumePath;
  std::string volumeChecksum;       // "sha256:…"
  std::string labelsPath;           // absolute or empty
  std::string labelsChecksum;       // empty when no labels
  std::string namesPath;            // absolute or empty
  Geometry geometry;                // of the volume
  std::string orientation;          // e.g. "LPS"
  std::string createdAt;            // ISO-8601 UTC, set by the database
  int structureCount = 0;           // filled by listDatasets/findDataset
};

// Stores a dataset and its structures in one transaction. A name already registered is an error
// naming it; nothing is written then.
Result<std::int64_t> registerDataset(Database& db, const DatasetRecord& record,
                                     const std::vector<Structure>& structures);

// All imported datasets, ordered by name.
Result<std::vector<DatasetRecord>> listDatasets(Database& db);

// The dataset called `name`, or nullopt.
Result<std::optional<DatasetRecord>> findDataset(Database& db, const std::string& name);

// A dataset's structures ordered by label.
Result<std::vector<Structure>> datasetStructures(Database& db, std::int64_t datasetId);

// The files to hand to openDatasetFiles for a registered dataset.
DatasetFiles datasetFiles(const DatasetRecord& record);

}  // namespace at::db
