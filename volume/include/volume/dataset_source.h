// Opening a dataset by name or path: "phantom" (256³), "phantom:128" (another size), or a volume
// path with optional labels/names. Imported datasets registered in the database are resolved by
// the app (db/) and then opened through openDatasetFiles.
#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>

#include "core/error.h"
#include "volume/intensity.h"
#include "volume/structure.h"

namespace at {

struct DatasetFiles {
  std::string volumePath;       // DICOM folder, .nii[.gz], .nrrd/.nhdr
  std::string labelsPath;       // optional: label map (any supported format, incl. DICOM SEG)
  std::string namesPath;        // optional: JSON { "value": "name" }
  std::string dicomSeriesUid;   // optional
  std::string id;               // dataset id to report
  IntensityChoice intensity = IntensityChoice::Auto;  // HU or plain intensities (volume/intensity.h)
  // Passed to the loaders (ImageLoadOptions): skip a DICOM folder's unreadable files with a note;
  // the folder a detached NRRD header may read data files from besides its own.
  bool skipUnreadableFiles = false;
  std::string dataFolder;
  // The user's rescale of the volume's values (applyRescale, volume/intensity.h): v·slope +
  // intercept; either alone takes the other's neutral value.
  std::optional<double> intercept, slope;
  // The DICOM Modality of a volume whose file records none ("MR" for an MR NIfTI, or an MR shared as a
  // course package's NRRD; a code as isDicomModalityCode takes): the dataset's modality, counted in
  // deciding its unit as a file's own. A file that records another modality is refused.
  std::string modality;
};

// "phantom" or "phantom:N" → the built-in phantom; anything else → error (the app resolves names).
Result<Dataset> openBuiltinDataset(const std::string& name);
bool isBuiltinDatasetName(const std::string& name);

// Progress and cancellation of openDatasetFiles (all optional). `progress` is called on the
// loading thread as each part starts (done = total = 0) and as its voxels are read (the loaders'
// units, see ImageLoadOptions::progress). Setting *cancel makes the load stop at the next check
// and fail with "<path>: loading cancelled".
enum class DatasetLoadPart { Volume, Labels, Resampling, Names };
struct DatasetLoadControl {
  std::function<void(DatasetLoadPart, std::size_t done, std::size_t total)> progress;
  const std::atomic<bool>* cancel = nullptr;
};

// Loads volume and labels, resamples labels onto the volume grid when their grids differ, and
// names structures from the file's segments, the names JSON, or "label_N".
Result<Dataset> openDatasetFiles(const DatasetFiles& files, const DatasetLoadControl& control = {});

}  // namespace at
