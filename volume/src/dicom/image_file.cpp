// loadImageFile: one entry point that picks the loader from the path.
#include "volume/image_file.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/strings.h"
#include "dicom_support.h"
#include "volume/dicom_seg.h"
#include "volume/dicom_series.h"
#include "volume/inv3_io.h"
#include "volume/nifti_io.h"
#include "volume/nrrd_io.h"
#include "core/regular_file.h"

namespace fs = std::filesystem;

namespace at {

namespace {


}  // namespace

Result<LoadedImage> loadImageFile(const std::string& path, const ImageLoadOptions& options) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) return fail(ErrorKind::NotFound, path + ": no such file or folder");
  if (fs::is_directory(status)) return loadDicomSeries(path, options);
  // FIFOs and devices are refused before anything opens them (opening a FIFO waits for a writer).
  if (auto regular = checkRegularFile(path, path); !regular) return tl::unexpected(regular.error());

  const std::string name = str::lower(fs::path(path).filename().string());
  if (str::endsWith(name, ".nii") || str::endsWith(name, ".nii.gz")) return loadNifti(path, options);
  if (str::endsWith(name, ".nrrd") || str::endsWith(name, ".nhdr")) return loadNrrd(path, options);
  if (str::endsWith(name, ".inv3")) return loadInv3(path, options);

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
  return fail(path + ": unrecognised format (expected a DICOM folder, .nii, .nii.gz, .nrrd, .nhdr or .inv3)");
}

}  // namespace at
