// Opening a dataset named on the command line, in a lesson or in the desktop, the same way
// everywhere: a built-in name (phantom, phantom:N), a dataset imported into the database
// (`anatomy-tutor import`; its structures with the names stored at import), or a path to a volume
// file or DICOM folder with optional labels and names.
#pragma once

#include <optional>
#include <set>
#include <string>
#include <vector>

#include "cli_args.h"
#include "core/error.h"
#include "volume/structure.h"

namespace at::db {
class Database;
}

namespace at::app {

struct DatasetRequest {
  std::string name;                   // built-in name, imported name or path
  std::string labelsPath;             // paths only: label map on any grid
  std::string namesPath;              // paths only: JSON { "value": "name" }
  std::string seriesUid;              // paths only: DICOM series
  std::string intensity;              // paths only: auto | hu | plain (volume/intensity.h); empty = auto
  // Where imported datasets are registered: the process's open connection when it has one (the
  // desktop, a lesson), else the database at dbPath (the default one when absent), opened only if
  // it exists.
  db::Database* database = nullptr;
  std::optional<std::string> dbPath;
  bool skipUnreadableFiles = false;   // paths only: --skip-unreadable (DICOM folders)
  std::string dataFolder;             // paths only: --nrrd-data DIR (detached NRRD data files)
  // paths only: --intercept B --slope M: the file's values v become v·M + B (a raw or NRRD CT
  // stored without its rescale, e.g. int16 with air at 0 and B = −1024). Values reaching air
  // (≤ −500) then make the volume CT in HU, unless --intensity plain says otherwise.
  std::string intercept, slope;
};

// A command's valued options plus the ones every dataset-taking command accepts beside its
// DATASET: --labels, --names, --series, --intensity, --nrrd-data, --intercept and --slope (datasets from files only;
// --db is global).
std::set<std::string> withDatasetOptions(std::set<std::string> commandOptions);
// A command's flags plus the dataset flag --skip-unreadable (datasets from files only).
std::set<std::string> withDatasetFlags(std::set<std::string> commandFlags);

// The help text of those options, for each command's --help.
inline constexpr const char* kDatasetOptionsHelp =
    "  --skip-unreadable  a DICOM folder's unreadable or broken files are skipped (named in a note)\n"
    "  --nrrd-data DIR    a detached NRRD header may read its data files under DIR (default: only\n"
    "                     under the header's own folder)\n"
    "  --intercept B --slope M  a volume file's values v read as v*M + B (a raw/NRRD CT stored without its\n"
    "                     rescale: --intercept -1024); values reaching air (<= -500) make it CT in HU\n"
    "                     (not for info, which describes the file as stored)\n";

// The request for dataset `name` with the dataset options given in `args`.
DatasetRequest datasetRequestFrom(const cli::Args& args, const std::string& name);

// Errors name what was tried ("unknown dataset 'abdomen': not built in, not imported in
// <db> (imported: …), and no such file or folder"); an unknown name is NotFound.
Result<Dataset> openNamedDataset(const DatasetRequest& request);

// The window that maps a dataset's stored values to density 0 … 1 for density weights: the HU
// window the caller has (a preset's, --hu-window) for CT, the dataset's own window (from its
// histogram) for plain intensities unless `windowGiven`. On a dataset whose intensities are not
// attenuation (MR) with density-based weights, says once per process on stderr that
// density-weighted distances assume CT-like values.
void applyDatasetWindow(const Dataset& dataset, float& windowMin, float& windowMax, bool windowGiven,
                        bool densityWeights);

// The one-line message for a structure `name` that `dataset` does not have: its structure ids (the
// first ten, then how many more), or, for a dataset without labels, how to give it some.
std::string unknownStructureMessage(const Dataset& dataset, const std::string& name);

}  // namespace at::app
