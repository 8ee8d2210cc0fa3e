// Importing a dataset into the database: what `anatomy-tutor import` and the desktop app's import
// panel both run, so that the two cannot drift apart. The volume and the optional labels and names
// are loaded (openDatasetFiles) to check that they align; the database keeps absolute paths,
// SHA-256 checksums, the geometry and the structures, never pixels or patient identifiers.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "db/dataset_store.h"
#include "core/error.h"
#include "volume/intensity.h"
#include "volume/structure.h"

namespace at::app {

struct ImportRequest {
  std::string volumePath;             // DICOM folder, .nii[.gz], .nrrd/.nhdr (relative: to the cwd)
  std::string labelsPath;             // optional label map (any of those or DICOM SEG)
  std::string namesPath;              // optional JSON {"1": "spleen", …}
  std::string name;                   // what commands will take as DATASET
  std::string species = "human";      // lower-case letters, '-' and '_'
  bool replace = false;               // a dataset of that name is replaced (its files changed)
  bool skipUnreadableFiles = false;   // a DICOM folder's unreadable files are skipped (kept for later opens)
  std::string dataFolder;             // a detached NRRD header may read data files here (kept too)
  // How the volume's values are read (kept too; DatasetFiles): a forced unit, and a rescale for a
  // volume whose file calibrates nothing (a raw volume, a CT stored without its rescale).
  IntensityChoice intensity = IntensityChoice::Auto;
  std::optional<double> intercept, slope;
  // The modality of a volume whose file records none (an MR NIfTI: "MR"; parseModalityCode), kept
  // too; empty: as the file says.
  std::string modality;
};

// The stages in the order they run.
enum class ImportStage { Checking, LoadingVolume, LoadingLabels, CheckingAlignment, Checksums, Storing };
const char* toString(ImportStage stage);  // "loading volume", …

// Optional progress and cancellation. `progress` is called on the importing thread as each stage
// starts (done = total = 0) and, while the volume or labels load, with the loaders' units (DICOM
// slices, NRRD data files, NIfTI bytes). Setting *cancel from any thread stops the import at its
// next check: it then fails with an ErrorKind::Cancelled error (message kImportCancelled) and has stored nothing. The last check is just
// before storing; once storing begins the import completes.
struct ImportControl {
  std::function<void(ImportStage, std::size_t done, std::size_t total)> progress;
  const std::atomic<bool>* cancel = nullptr;
};
inline constexpr const char* kImportCancelled = "import cancelled; nothing was stored";

struct ImportedDataset {
  db::DatasetRecord record;                  // as stored (id, paths, checksums, geometry)
  Dataset dataset;                           // as loaded, so the app can show it without loading again
  std::vector<std::string> emptyStructures;  // named structures with no voxel on the volume grid
};

// Validates the request (name not built in and not taken, species, files exist), loads, checks
// alignment, checksums the files and registers the dataset in `database` in one transaction.
// Errors are one line naming the file or field and the problem (a taken name is a Conflict, a
// cancelled import Cancelled); nothing is stored then. May run on another thread than the
// connection's other users (db/connection.h).
Result<ImportedDataset> importDataset(db::Database& database, const ImportRequest& request,
                                      const ImportControl& control = {});

}  // namespace at::app
