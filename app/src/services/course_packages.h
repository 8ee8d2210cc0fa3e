// Course packages on this machine (package/course_package.h holds the format): exporting a stored
// course with its presets and dataset, and importing a package into the database with its assets
// under the database's data folder, so that nothing refers to where the package or the author's
// files were. `anatomy-tutor course export|import` and the desktop's Open course… run these.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "db/course_store.h"
#include "learning_session.h"
#include "package/course_package.h"
#include "render/preset.h"

namespace at::app {

// Where imported course assets live: beside the database, in "<db stem>-data/" (for the default
// database $XDG_DATA_HOME/anatomy-tutor/anatomy-tutor-data/). Datasets go to datasets/<name>/, and the
// database records them relative to its own folder. For a class server (postgresql://): this
// machine's folder for the server (db::datasetPathBase), so that the server holds the course's rows
// once and each lab machine that imports the package has the files.
Result<std::filesystem::path> courseAssetDirectory(const db::Database& database);

struct CourseExportRequest {
  std::string courseId;
  std::filesystem::path out;          // the .atcourse file to write
  bool referenceVolume = false;       // leave the volume out: the importer supplies it by checksum
  std::string referenceNote;          // with referenceVolume: where to get the scan, its licence
};

struct CourseExportReport {
  std::filesystem::path file;
  std::uintmax_t bytes = 0;
  package::VolumeSource source = package::VolumeSource::Builtin;
  std::string datasetId;
  std::size_t presets = 0, structures = 0;
};

// Writes the stored course `courseId` as a package: its course JSON, the presets its steps name
// (from the database's presets, else the shipped `library`), and for an imported dataset its
// structures, label map and (unless referenceVolume) volume, written from the loaded voxels.
// Errors: an unknown course, a structure the dataset lacks (by field path), an unwritable file.
Result<CourseExportReport> exportCourse(LearningSession& session, const render::PresetLibrary& library,
                                        const CourseExportRequest& request);

struct CourseImportRequest {
  std::filesystem::path package;
  // For a package that references its volume: the scan the author named (file or DICOM folder),
  // checked against the recorded checksum and copied into the data folder.
  std::string volumePath;
};

// PlacedHere: a class server already had the dataset (another machine imported the package);
// this import put its files on this machine.
enum class DatasetAction { Builtin, Imported, AlreadyPresent, PlacedHere };
const char* toString(DatasetAction action);  // "built in", "imported", "already present", …

struct CourseImportReport {
  std::string courseId, courseTitle;
  int version = 0;
  db::SeedOutcome outcome = db::SeedOutcome::Added;
  std::string datasetId;
  DatasetAction dataset = DatasetAction::Builtin;
  std::filesystem::path datasetFolder;   // Imported: where its files now are
  // The package's presets as stored, under the course's keys ("<course>/<id>", course_presets.h);
  // empty when the course was Unchanged (nothing written).
  std::vector<std::string> presetsStored;
};

// Verifies and imports a package, all or nothing: the files are extracted into a staging folder
// of the data folder and checked there, the dataset, the presets and the course are stored in one
// database transaction, and the files are moved into datasets/<name> after it commits; a crash
// at any point leaves the old state or the new one (import_staging.h finishes or removes what a
// crash left). Names from the package (dataset, course, presets) follow core/safe_name.h and every
// path is built with confinedPath. The package's presets are stored for its course only
// (course_presets.h): never in place of a shipped preset or another course's.
// Refused, with one line and nothing stored: any failed check of the package; a course id stored
// with another dataset, a newer version, or different content under the same version; lesson,
// question or exam ids another course uses; a dataset name already imported with another volume
// (or a datasets/<name> folder no stored dataset owns); a referenced volume missing or with
// another checksum; a structure the course names that the dataset lacks; a failed write (a full
// disk). The same package imported twice is Unchanged.
Result<CourseImportReport> importCoursePackage(LearningSession& session, const CourseImportRequest& request);

}  // namespace at::app
