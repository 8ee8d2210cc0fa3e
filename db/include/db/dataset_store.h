// Imported datasets: where their files are (absolute paths + checksums), their geometry and
// species, and their structures. Never pixel data, never patient identifiers.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "db/connection.h"
#include "volume/dataset_source.h"
#include "volume/geometry.h"
#include "volume/structure.h"

namespace at::db {

// An instructor's review of a structure's labels, set in the segment editor and stored with the
// structure (structures.review_state). Instructor metadata: never shown to students as content.
enum class ReviewState { NotStarted, InProgress, Completed, Flagged };
inline constexpr ReviewState kReviewStates[] = {ReviewState::NotStarted, ReviewState::InProgress, ReviewState::Completed,
                                                ReviewState::Flagged};
// "not_started", "in_progress", "completed", "flagged" (stored and in UI scripts).
const char* reviewStateId(ReviewState state);
// "not started", "in progress", "completed", "flagged" (the editor's list).
const char* reviewStateText(ReviewState state);
// From an id or a text above; nullopt for anything else.
std::optional<ReviewState> reviewStateNamed(const std::string& name);
// Structure id → review state; a structure not in the map is not started.
using ReviewStates = std::map<std::string, ReviewState>;

struct DatasetRecord {
  std::int64_t id = 0;
  std::string name;                 // unique; what commands take as DATASET
  std::string species = "human";
  // Paths are absolute, or stored relative to datasetPathBase (a course package's dataset, kept in
  // the database's data folder: the two move together) and read back absolute.
  std::string volumePath;
  std::string volumeChecksum;       // "sha256:…"
  std::string labelsPath;           // absolute or empty
  std::string labelsChecksum;       // empty when no labels
  std::string namesPath;            // absolute or empty
  bool skipUnreadableFiles = false; // how the files are read (DatasetFiles): as at import
  std::string dataFolder;           // absolute or empty
  // How the volume's values are read, as at import (DatasetFiles): the unit asked for and the
  // user's rescale (--intensity, --intercept, --slope).
  IntensityChoice intensity = IntensityChoice::Auto;
  std::optional<double> intercept, slope;
  // The volume's DICOM Modality where its file has none (DatasetFiles::modality): "MR" for an MR
  // NIfTI imported with --modality MR, or an MR from a course package. Upper-case letters, digits,
  // '_' and ' ', at most 16 (DICOM's CS).
  std::string modality;
  Geometry geometry;                // of the volume
  std::string orientation;          // e.g. "LPS"
  std::string createdAt;            // ISO-8601 UTC, set by the database
  int structureCount = 0;           // filled by listDatasets/findDataset
};

// The folder relative dataset paths are stored against, on this machine: a database file's
// folder; for a class server (postgresql://) this machine's own folder for that server,
// $XDG_DATA_HOME/anatomy-tutor/servers/<server>/ (<server>: the URL without its user and password
// as a file name). A course package imported into a server keeps the dataset's row there once and
// its files on each lab machine that imports it, at the same relative paths.
Result<std::string> datasetPathBase(const Database& db);

// Stores a dataset and its structures in one transaction. A name already registered is an error
// naming it (nothing is written then) unless `replace` is set: then the earlier record and its
// structures are replaced in that same transaction (courses and progress refer to datasets and
// structures by name and id, so they carry over).
Result<std::int64_t> registerDataset(Database& db, const DatasetRecord& record,
                                     const std::vector<Structure>& structures, bool replace = false);

// Replaces an imported dataset's labels after editing: the label map file and names file the
// caller wrote (absolute paths; the checksum of the label file) and its structures, in one
// transaction; the volume and the geometry stay. Review states: `review` when given (structures
// not in it: not started), else each structure keeps the state stored under its id. NotFound when
// no dataset has that name (nothing is written then).
Status saveDatasetLabels(Database& db, const std::string& name, const std::string& labelsPath,
                         const std::string& labelsChecksum, const std::string& namesPath,
                         const std::vector<Structure>& structures, const ReviewStates* review = nullptr);

// Gives structure `structureId` of imported dataset `name` the browsing group `system` ("middle
// ear", "skull bones", …; empty clears it). NotFound names the dataset or the structure (nothing is
// written then); the stored label map and names file are not touched.
Status setStructureSystem(Database& db, const std::string& name, const std::string& structureId,
                          const std::string& system);

// The review states stored for dataset `datasetId`'s structures (every structure, by id).
Result<ReviewStates> datasetReviewStates(Database& db, std::int64_t datasetId);

// All imported datasets, ordered by name.
Result<std::vector<DatasetRecord>> listDatasets(Database& db);

// The dataset called `name`, or nullopt.
Result<std::optional<DatasetRecord>> findDataset(Database& db, const std::string& name);

// A dataset's structures ordered by label.
Result<std::vector<Structure>> datasetStructures(Database& db, std::int64_t datasetId);

// The files to hand to openDatasetFiles for a registered dataset.
DatasetFiles datasetFiles(const DatasetRecord& record);

// The import options that say how its values are read, as command-line arguments (" --intensity
// hu --intercept -1024 --modality MR"; empty when none was given): for messages that tell how to
// import again.
std::string loadOptionArguments(const DatasetRecord& record);

// The same, once the volume's and the labels' checksums are those recorded at import: a file
// replaced or changed since (even by one on the same grid) is a Conflict naming the file, both
// checksums, and the command that registers the new content (import … --replace).
Result<DatasetFiles> verifiedDatasetFiles(const DatasetRecord& record);

}  // namespace at::db
