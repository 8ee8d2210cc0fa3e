// Course packages (.atcourse): one file that carries a course to another machine — the course JSON,
// the presets its steps use, the dataset's structures and label map, and its volume (or, for a scan
// that may not be redistributed, a reference by content hash with a download note).
//
// The container is a POSIX tar archive written and read with libarchive (gzip-compressed tars are
// read too). Format version 2 holds, in this order:
//
//   manifest.json            format name and version, the course's id/version/title/dataset, the
//                            dataset entry, and every other file with its size and SHA-256
//   course.json              the course (lessons/course_json.h schema)
//   presets/<id>.json        each preset the course uses (render/preset.h schema), <id> = preset id
//   dataset/structures.json  [{label, id, name, colour, system, description}] (not for built-ins)
//   dataset/labels.nrrd      the label map on the volume's grid (uint16 NRRD; when it has one)
//   dataset/volume.nrrd      the volume (int16 NRRD, LPS; only when included)
//
// Version 2 adds the dataset entry's `reading` (how the volume file's values are read); a package
// without one is written as version 1, which earlier programs read.
//
// Reading verifies as it streams: manifest.json first; then each entry must be a regular file
// listed in the manifest at one of the names above, of the listed size and SHA-256; at the end
// every listed file must have come. Names are relative, without "..", "." or empty components,
// absolute paths or backslashes; links, devices and folders are refused. Sizes are bounded by
// ReadLimits before anything is allocated. The course id, a non-built-in dataset's name and
// every preset id must be safe names (core/safe_name.h): they become keys and folder names. Nothing is written outside `extractTo`, and there only
// under fixed names (volume.nrrd, labels.nrrd): entry names never become file paths.
//
// This module knows no database: the app stores what it reads (app/src/services/course_packages.h).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "lessons/curriculum.h"
#include "render/preset.h"
#include "volume/geometry.h"
#include "volume/intensity.h"
#include "volume/structure.h"

namespace at::package {

inline constexpr const char* kFormatName = "anatomy-tutor-course";
inline constexpr int kFormatVersion = 2;  // the newest this program reads and writes
inline constexpr const char* kExtension = ".atcourse";

// Where the dataset's volume comes from on the machine that imports the package.
enum class VolumeSource {
  Builtin,    // a dataset every copy of the program opens by name (phantom, phantom:N, skull)
  Included,   // dataset/volume.nrrd in the package
  Reference,  // not in the package: the importer supplies a file with the recorded checksum
};
const char* toString(VolumeSource source);  // "builtin", "included", "reference"

// How the importer reads the dataset's volume file: the loader's options (DatasetFiles,
// volume/intensity.h) — the unit forced, and value = file value · slope + intercept. A package
// records one where the file read by itself would give other values than the author's: an included
// volume of plain intensities stored shifted or scaled to fit int16 (a 16-bit µCT), or whose values
// reach −500 (read as HU otherwise), or of HU without air (read as plain otherwise); a referenced
// file the author imported with --intensity, --intercept, --slope or --skip-unreadable; an included
// MR's modality.
struct VolumeReading {
  IntensityChoice intensity = IntensityChoice::Auto;
  std::optional<double> intercept, slope;
  bool skipUnreadableFiles = false;  // a DICOM folder's unreadable files skipped, as the author's were
  // The volume's DICOM Modality where the package's file does not give it and it matters: "MR" (its
  // intensities are not attenuation, so density-weighted distances carry a note); empty otherwise.
  std::string modality;
};

struct DatasetEntry {
  std::string name;                   // the course's dataset id
  VolumeSource source = VolumeSource::Builtin;
  std::string species = "human";
  std::optional<Geometry> geometry;   // the volume's grid (included and reference)
  // "sha256:<hex>" of the volume file or folder the author imported (db/checksum.h): what a
  // Reference asks for; for Included, the same dataset already imported under this name is
  // recognised by it.
  std::string sourceVolumeChecksum;
  std::string sourceLabelsChecksum;   // likewise for the author's label file ("" without labels)
  std::string referenceFileName;      // Reference: the file's name as distributed ("Cranium.inv3")
  std::string referenceNote;          // Reference: where to get it and under which licence
  std::optional<VolumeReading> reading;  // included and reference only; none: read as the file says
};

struct PackagedFile {
  std::string path;       // name inside the package ("dataset/volume.nrrd")
  std::uint64_t size = 0;
  std::string sha256;     // 64 lowercase hex digits
};

struct Manifest {
  int formatVersion = kFormatVersion;
  std::string createdBy;  // "anatomy-tutor 0.1.0"
  std::string courseId;
  int courseVersion = 1;
  std::string courseTitle;
  DatasetEntry dataset;
  std::vector<PackagedFile> files;  // every entry but manifest.json
  const PackagedFile* find(const std::string& path) const;
};

// A preset the course uses, with its JSON text as written.
struct PackagedPreset {
  std::string id;
  render::Preset preset;
  std::string json;
};

// What reading gives.
struct CoursePackage {
  Manifest manifest;
  lessons::Course course;
  std::string courseJson;                 // course.json as stored
  std::vector<PackagedPreset> presets;    // sorted by id
  std::vector<Structure> structures;      // empty for a built-in dataset
  // Where the data files were written (only when ReadOptions::extractTo was given and the package
  // has them; else empty).
  std::filesystem::path volumeFile, labelsFile;
  bool hasLabels = false;
};

// Bounds on what a package may make the reader allocate or write, fitted to real content (a
// preset is a few KB, a course with its questions a few hundred KB, the skull's structures
// 20 KB). Declared sizes are checked before a byte of the entry is read, and the bytes read are
// counted as they stream: a bomb is refused after at most one limit's worth of memory.
struct ReadLimits {
  std::uint64_t maxEntries = 1024;
  std::uint64_t maxManifestBytes = std::uint64_t(1) << 20;
  std::uint64_t maxCourseBytes = std::uint64_t(4) << 20;
  std::uint64_t maxPresetBytes = std::uint64_t(64) << 10;    // one presets/<id>.json
  std::uint64_t maxStructuresBytes = std::uint64_t(4) << 20;
  std::uint64_t maxDocumentsBytes = std::uint64_t(16) << 20;  // every document above together
  std::uint64_t maxDataBytes = std::uint64_t(8) << 30;        // the volume or the label map
  std::uint64_t maxTotalBytes = std::uint64_t(12) << 30;      // all entries together
};

struct ReadOptions {
  ReadLimits limits;
  // A folder (existing, normally empty) to write the volume and label map into as volume.nrrd
  // and labels.nrrd; without one they are checked and discarded.
  std::optional<std::filesystem::path> extractTo;
};

// Reads and verifies a package. Errors are one line naming the package (`name`, or the file's
// path) and the entry or field: a checksum mismatch (with both checksums), a missing or unlisted
// entry, a newer format version, an unsafe name, a link, a limit exceeded, a course that does not
// parse (its field path). Invalid for a damaged or altered package, Unavailable for a newer
// format, Io when the file cannot be read. On error nothing is left in `extractTo` that reading
// wrote.
Result<CoursePackage> readPackageFile(const std::filesystem::path& file, const ReadOptions& options = {});
Result<CoursePackage> readPackageBytes(std::string_view bytes, const std::string& name, const ReadOptions& options = {});

// What a package is written from. The data files are written by the caller (writeDatasetFiles).
struct PackageInput {
  lessons::Course course;
  std::vector<PackagedPreset> presets;
  DatasetEntry dataset;
  std::vector<Structure> structures;      // not for built-ins
  std::filesystem::path volumeFile;       // Included: an int16 NRRD of the volume
  std::filesystem::path labelsFile;       // optional: a uint16 NRRD of the labels on the same grid
  std::string createdBy;
};

// Writes `input` to `out` (through a temporary file beside it, renamed at the end: an existing
// file is replaced only by a complete package). The entries are written in a fixed order with
// fixed times and owners, so the same input gives the same bytes.
Status writePackage(const std::filesystem::path& out, const PackageInput& input);

// Writes a dataset's volume (int16) and label map (uint16) into `dir` as volume.nrrd and
// labels.nrrd (the labels only when `withLabels`). The volume is written from the loaded voxels,
// so no header field of the original files (patient identifiers in DICOM) travels.
struct DatasetFilesWritten {
  std::filesystem::path volume, labels;
};
Result<DatasetFilesWritten> writeDatasetFiles(const Dataset& dataset, const std::filesystem::path& dir, bool withLabels);
// How the importer must read the volume.nrrd writeDatasetFiles wrote from `dataset` to get the
// dataset's values and unit back (none where reading it by itself does: HU with air, or plain
// intensities stored as they are, none down to −500).
std::optional<VolumeReading> includedVolumeReading(const Dataset& dataset);

// Structures as dataset/structures.json holds them, and back (strict: unknown fields, repeated
// labels or ids, colours outside 0..1 are errors naming the entry).
std::string structuresToJson(const std::vector<Structure>& structures);
Result<std::vector<Structure>> parseStructuresJson(std::string_view text, const std::string& source);

// The manifest as JSON text, and back (strict; a newer format version is an Unavailable error).
std::string manifestToJson(const Manifest& manifest);
Result<Manifest> parseManifest(std::string_view text, const std::string& source);

// True for a name a package may hold: relative, '/'-separated components of letters, digits,
// '_', '-', '.', none empty, none starting with '.', at most 200 characters.
bool safeEntryName(std::string_view name);

}  // namespace at::package
