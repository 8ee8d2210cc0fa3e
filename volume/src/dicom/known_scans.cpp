// Known scans: built-in names for real scans that set-up fetches from Debian packages.
#include "volume/known_scans.h"

#include <cstdlib>

namespace fs = std::filesystem;

namespace at {

const std::vector<KnownScan>& knownScans() {
  static const std::vector<KnownScan> scans = {
      {"skull", "Head CT (InVesalius example 'Cranium', 256x256x108, 0.96 x 0.96 x 1.5 mm)", "invesalius-examples",
       "GPL-2", "Cranium.inv3", "/usr/share/doc/invesalius-examples/examples/Cranium.inv3"},
  };
  return scans;
}

const KnownScan* findKnownScan(const std::string& name) {
  for (const KnownScan& scan : knownScans())
    if (scan.name == name) return &scan;
  return nullptr;
}

fs::path knownScanCacheDir() {
  if (const char* cache = std::getenv("XDG_CACHE_HOME"); cache && *cache) return fs::path(cache) / "anatomy-tutor" / "scans";
  if (const char* home = std::getenv("HOME"); home && *home) return fs::path(home) / ".cache" / "anatomy-tutor" / "scans";
  return fs::path(".cache") / "anatomy-tutor" / "scans";
}

std::vector<fs::path> knownScanCandidates(const KnownScan& scan) {
  return {knownScanCacheDir() / scan.debianPackage / scan.fileName, scan.packagePath};
}

std::optional<fs::path> locateKnownScan(const KnownScan& scan) {
  for (const fs::path& candidate : knownScanCandidates(scan)) {
    std::error_code ec;
    if (fs::is_regular_file(candidate, ec)) return candidate;
  }
  return std::nullopt;
}

Result<fs::path> knownScanFile(const KnownScan& scan) {
  if (auto path = locateKnownScan(scan)) return *path;
  std::string looked;
  for (const fs::path& candidate : knownScanCandidates(scan)) looked += (looked.empty() ? "" : ", ") + candidate.string();
  return fail(ErrorKind::NotFound, "dataset '" + scan.name + "' is " + scan.fileName + " from Debian's " + scan.debianPackage +
              " package, which is not here (looked for " + looked + "): fetch it with `bash scripts/fetch-scans.sh` "
              "(also installed as share/anatomy-tutor/fetch-scans.sh) or `sudo apt-get install " + scan.debianPackage + "`");
}

std::optional<KnownScanLabels> cachedKnownScanLabels(const KnownScan& scan) {
  const fs::path dir = knownScanCacheDir() / scan.debianPackage;
  KnownScanLabels labels{(dir / (scan.name + ".labels.nii.gz")).string(), (dir / (scan.name + ".labels.names.json")).string()};
  std::error_code ec;
  if (!fs::is_regular_file(labels.labelsPath, ec) || !fs::is_regular_file(labels.namesPath, ec)) return std::nullopt;
  return labels;
}

Result<Dataset> openKnownScan(const KnownScan& scan, const KnownScanLabels& given, const DatasetLoadControl& control) {
  auto path = knownScanFile(scan);
  if (!path) return tl::unexpected(path.error());
  KnownScanLabels labels = given;
  if (labels.labelsPath.empty())
    if (auto cached = cachedKnownScanLabels(scan)) labels = *cached;
  DatasetFiles files;
  files.volumePath = path->string();
  files.id = scan.name;
  files.labelsPath = labels.labelsPath;
  files.namesPath = labels.namesPath;
  auto dataset = openDatasetFiles(files, control);
  if (!dataset) return tl::unexpected(dataset.error());
  dataset->displayName = scan.title;
  dataset->provenance.notes.push_back(scan.fileName + " from Debian's " + scan.debianPackage + " package (" + scan.licence + ")");
  return dataset;
}

}  // namespace at
