// Real scans opened by a built-in name that set-up fetches from a Debian package; the repository
// never carries them. Today one: "skull", the head CT `Cranium.inv3` of Debian's
// `invesalius-examples` (GPL-2), which `scripts/fetch-scans.sh` downloads with `apt-get download`
// and unpacks into the cache folder.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "volume/dataset_source.h"
#include "core/error.h"
#include "volume/structure.h"

namespace at {

struct KnownScan {
  std::string name;           // the dataset name: "skull"
  std::string title;          // "Head CT (InVesalius example 'Cranium')"
  std::string debianPackage;  // "invesalius-examples"
  std::string licence;        // "GPL-2"
  std::string fileName;       // "Cranium.inv3"
  std::filesystem::path packagePath;  // where the installed package puts it
};

const std::vector<KnownScan>& knownScans();
// The scan called `name`, or nullptr.
const KnownScan* findKnownScan(const std::string& name);

// The folder fetch-scans.sh unpacks into: $XDG_CACHE_HOME/anatomy-tutor/scans (default
// ~/.cache/anatomy-tutor/scans), one sub-folder per Debian package.
std::filesystem::path knownScanCacheDir();

// Where the scan's file is looked for, in order: the cache folder, then the installed package.
std::vector<std::filesystem::path> knownScanCandidates(const KnownScan& scan);
// The first candidate that exists, if any.
std::optional<std::filesystem::path> locateKnownScan(const KnownScan& scan);
// The same, or an error that says where the file was looked for and how to fetch it.
Result<std::filesystem::path> knownScanFile(const KnownScan& scan);

// Labels drawn on a known scan (optional): a label map on any grid and a names JSON, as for a
// dataset from files.
struct KnownScanLabels {
  std::string labelsPath;
  std::string namesPath;
};

// The labels scripts/label-scans.sh writes beside the scan in the cache folder
// (<name>.labels.nii.gz and <name>.labels.names.json, grown by `anatomy-tutor segment` from the
// seeds in data/segmentations/<name>/), when both files are there.
std::optional<KnownScanLabels> cachedKnownScanLabels(const KnownScan& scan);

// Opens the scan as a dataset named scan.name, with `labels` when given, else with its cached
// labels when there are some; fails as knownScanFile does when the scan's file is absent.
Result<Dataset> openKnownScan(const KnownScan& scan, const KnownScanLabels& labels = {},
                              const DatasetLoadControl& control = {});

}  // namespace at
