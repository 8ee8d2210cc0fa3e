// The dataset options of the command line: what every dataset-taking command accepts beside its
// DATASET, read into a DatasetRequest (services/dataset_resolver.h opens it), and the density
// window's note on stderr.
#pragma once

#include <set>
#include <string>

#include "cli_args.h"
#include "dataset_resolver.h"

namespace at::app {

// A command's valued options plus the ones every dataset-taking command accepts beside its
// DATASET: --labels, --names, --series, --intensity, --nrrd-data, --intercept, --slope and
// --modality (datasets from files only; --db is global).
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
    "                     (not for info, which describes the file as stored)\n"
    "  --modality CODE    the DICOM modality of a file that records none (an MR NIfTI or NRRD: MR); on\n"
    "                     MR, PT, NM, US, … density-weighted distances come with a note\n";

// The request for dataset `name` with the dataset options given in `args`.
DatasetRequest datasetRequestFrom(const cli::Args& args, const std::string& name);

// Says on stderr, one line each, what the dataset's files leave the user to check (a label map off
// its volume, labels lost to resampling: Provenance::warnings), as `import` does.
void reportDatasetWarnings(const Dataset& dataset);

// The window that maps a dataset's stored values to density 0 … 1 for density weights: the HU
// window the caller has (a preset's, --hu-window) for CT, the dataset's own window (from its
// histogram) for plain intensities unless `windowGiven`. On a dataset whose intensities are not
// attenuation (MR) with density-based weights, says once per process on stderr that
// density-weighted distances assume CT-like values.
void applyDatasetWindow(const Dataset& dataset, float& windowMin, float& windowMax, bool windowGiven,
                        bool densityWeights);

}  // namespace at::app
