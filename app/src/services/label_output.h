// Where labels made in the app go (the `segment` command and the desktop's segment editor): a label
// map file (NIfTI with an optional names JSON, or a Slicer .seg.nrrd), and the dataset store, where
// an imported dataset's labels are replaced by new ones that every command then opens.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/error.h"
#include "db/connection.h"
#include "db/dataset_store.h"
#include "volume/structure.h"

namespace at::app {

// A label map file name this app writes: .nii, .nii.gz or .seg.nrrd (the error names the path).
Status checkLabelsPath(const std::filesystem::path& out);
// Writes the labels as `out` says (checkLabelsPath); errors name the file.
Status writeLabelsFile(const std::filesystem::path& out, const LabelMap& labels, const std::vector<Structure>& structures);

// Stores the labels of the imported dataset `datasetName`: a NIfTI label map and names JSON under
// <database folder>/labels/ (stamped with the time), recorded as the dataset's labels. Returns the
// label map's path. `review`: the structures' review states (null: each keeps the stored one,
// db::saveDatasetLabels). Errors: NotFound when `datasetName` is not an imported dataset (nothing
// is written then), Unavailable on a PostgreSQL class server (the files need a folder), Io for
// files that cannot be written.
Result<std::string> storeDatasetLabels(db::Database& database, const std::string& datasetName, const LabelMap& labels,
                                       const std::vector<Structure>& structures,
                                       const db::ReviewStates* review = nullptr);

}  // namespace at::app
