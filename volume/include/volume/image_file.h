// Reading images from files: what every loader returns, and one entry point that picks the loader
// from the path (a folder → DICOM series; .nii/.nii.gz → NIfTI; .nrrd/.nhdr/.seg.nrrd → NRRD;
// .inv3 → InVesalius project; a DICOM SEG file → segmentation). Only geometry and pixel data survive loading: no patient
// identifiers (name, ID, birth date, institution, accession, dates) are ever copied out.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "core/error.h"
#include "volume/grid.h"
#include "volume/intensity.h"

namespace at {

enum class ScalarKind { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };
const char* toString(ScalarKind kind);

// A segment (label value and its name) that a file names itself: NRRD Segment<N>_* keys,
// DICOM SEG SegmentSequence.
struct SegmentInfo {
  std::uint16_t label = 0;
  std::string name;
  std::array<float, 3> colour{1, 1, 1};
};

struct LoadedImage {
  FloatVolume image;                 // values after rescale (HU for CT), on the file's geometry
  ScalarKind storedKind = ScalarKind::Int16;  // how the file stored them
  std::vector<SegmentInfo> segments; // segment names found in the file (may be empty)
  std::vector<std::string> notes;    // e.g. "chose series 1.2.3 (20 of 23 files)"
  std::string modality;              // DICOM Modality ("CT", "MR", …); empty where the format has none
  bool rescaleGiven = false;         // DICOM RescaleSlope/Intercept or NIfTI scl_slope were in the file
};

struct ImageLoadOptions {
  std::string dicomSeriesUid;        // DICOM folders: this series; empty → the largest
  // Refuse images whose load would peak above this many bytes: the float voxels, their 2-byte HU or
  // label copy and the loader's buffers (0 = imageMemoryBudget(), from the memory free to this process).
  std::size_t maxBytes = 0;
  // Optional, for long loads: `progress` receives (parts read, parts in total) as the voxels are
  // read (a DICOM series: slices; a detached NRRD: data files; NIfTI: bytes of voxel data), from
  // the loading threads but never concurrently. Setting *cancel from any thread makes the loader stop at its
  // next check and fail with "<path>: loading cancelled".
  std::function<void(std::size_t, std::size_t)> progress;
  const std::atomic<bool>* cancel = nullptr;
  // A detached NRRD header may name data files only inside its own folder (a course package's
  // header must not read the user's files). A folder named here, by the user, is allowed instead.
  std::string dataFolder;
  // DICOM folders: files that cannot be read, or whose own header is broken (truncated pixel data,
  // an unsupported transfer syntax), are skipped and named in a note instead of failing the load.
  bool skipUnreadableFiles = false;
};

// Loads any supported input, choosing the loader from the path.
Result<LoadedImage> loadImageFile(const std::string& path, const ImageLoadOptions& options = {});

// Converts a loaded image to HU int16; errors if values are not finite or lie outside int16.
Result<Volume> toHuVolume(const LoadedImage& loaded, const std::string& pathForMessages);

// A loaded image as a dataset's int16 volume with its intensity model (volume/intensity.h): the
// unit decided by decideIntensity (or forced by `choice`); HU stored as they are; plain
// intensities stored as they are where they fit int16 as integers, else shifted (uint16 above
// 32767) or scaled (fractional values, wider ranges) to fit, the model's slope and intercept
// giving the file's values back. Errors name the voxel: non-finite values, HU outside int16.
struct StoredVolume {
  Volume volume;
  IntensityModel intensity;
};
Result<StoredVolume> toStoredVolume(const LoadedImage& loaded, const std::string& pathForMessages,
                                    IntensityChoice choice = IntensityChoice::Auto);
// A modality the user gives (`given`, a code as parseModalityCode returns it; empty: none) for an
// image whose file records none: it becomes the image's (with a note saying so), and toStoredVolume
// counts it as the file's own. A file that records another modality is refused, naming `pathForMessages`.
Status takeGivenModality(LoadedImage& loaded, const std::string& given, const std::string& pathForMessages);
// Converts a loaded image to labels; errors if values are negative, non-integer or > 65535.
Result<LabelMap> toLabelMap(const LoadedImage& loaded, const std::string& pathForMessages);

// Reads a JSON map { "1": "spleen", "2": "kidney_right", … } of label value → name.
Result<std::map<std::uint16_t, std::string>> loadLabelNames(const std::string& path);

// How much memory one image load may use, and where that limit comes from.
struct MemoryBudget {
  std::size_t bytes = 0;
  std::string source;  // for messages: "3/4 of the 5.1 GiB free under this process's cgroup memory limit"
};
// Where the memory figures are read from (tests point these at files of their own).
struct MemoryInfoFiles {
  std::string meminfo = "/proc/meminfo";
  std::string selfCgroup = "/proc/self/cgroup";
  std::string cgroupRoot = "/sys/fs/cgroup";
};
// 3/4 of the memory free to this process: the smaller of the machine's MemAvailable and, when the
// process runs in a memory-limited cgroup (v1 or v2, any level of its hierarchy), that limit minus
// the cgroup's use (reclaimable file cache not counted). 2 GiB when neither can be read.
MemoryBudget imageMemoryBudget(const MemoryInfoFiles& files = {});
// imageMemoryBudget().bytes.
std::size_t availableImageBytes();

}  // namespace at
