// Opening a dataset named on the command line, in a lesson or in the desktop, the same way
// everywhere (the command line's dataset options: cli/dataset_options.h): a built-in name (phantom, phantom:N), a dataset imported into the database
// (`anatomy-tutor import`; its structures with the names stored at import), or a path to a volume
// file or DICOM folder with optional labels and names.
#pragma once

#include <optional>
#include <string>
#include <vector>

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
  // paths only: --modality CODE for a file that records none (an MR NIfTI: MR), as parseModalityCode
  // takes it; a file that records another is refused.
  std::string modality;
};

// Errors name what was tried ("unknown dataset 'abdomen': not built in, not imported in
// <db> (imported: …), and no such file or folder"); an unknown name is NotFound.
Result<Dataset> openNamedDataset(const DatasetRequest& request);

// The one-line message for a structure `name` that `dataset` does not have: its structure ids (the
// first ten, then how many more), or, for a dataset without labels, how to give it some.
std::string unknownStructureMessage(const Dataset& dataset, const std::string& name);

}  // namespace at::app
