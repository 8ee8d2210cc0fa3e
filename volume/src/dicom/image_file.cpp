// loadImageFile: one entry point that picks the loader from the path.
#include "volume/image_file.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "dicom_support.h"
#include "volume/dicom_seg.h"
#include "volume/dicom_series.h"
#include "volume/nifti_io.h"
#include "volume/nrrd_io.h"
#include "volume/regular_file.h"

namespace fs = std::filesystem;

namespace at {

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

Result<LoadedImage> loadImageFile(const std::string& path, const ImageLoadOptions& options) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) return fail(path + ": no such file or folder");
  if (fs::is_directory(status)) return loadDicomSeries(path, options);
  // FIFOs and devices are refused before anything opens them (opening a FIFO waits for a writer).
  if (auto regular = checkRegularFile(path, path); !regular) return tl::unexpected(regular.error());

  std::string name = fs::path(path).filename().string();
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  if (endsWith(name, ".nii") || endsWith(name, ".nii.gz")) return loadNifti(path, options);
  if (endsWith(name, ".nrrd") || endsWith(name, ".nhdr")) return loadNrrd(path, options);

  if (looksLikeDicomFile(path)) {
    if (isDicomSegFile(path)) return loadDicomSeg(path, options);
    // One image of a series: load the whole series from its folder, restricted to the file's series.
    // (A file without SeriesInstanceUID gets the folder's largest series, as a folder would.)
    auto uid = dicom::readSeriesInstanceUid(path);
    if (!uid) return tl::unexpected(uid.error());
    ImageLoadOptions seriesOptions = options;
    seriesOptions.dicomSeriesUid = *uid;
    fs::path folder = fs::path(path).parent_path();
    if (folder.empty()) folder = ".";
    auto loaded = loadDicomSeries(folder.string(), seriesOptions);
    if (!loaded) return loaded;
    loaded->notes.push_back("loaded the whole series of " + fs::path(path).filename().string() + " from its folder");
    return loaded;
  }
  return fail(path + ": unrecognised format (expected a DICOM folder, .nii, .nii.gz, .nrrd or .nhdr)");
}

}  // namespace at
