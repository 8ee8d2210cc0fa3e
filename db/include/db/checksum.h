// Content checksums for the files a dataset references (the database stores paths + checksums,
// never pixels), so a moved or modified file is noticed.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "core/error.h"
#include "core/sha256.h"

namespace at::db {

// SHA-256 of a byte string, as 64 lowercase hex digits (core/sha256.h).
using at::sha256Hex;

// "sha256:<hex>" of a file's bytes, or for a folder (a DICOM series) of the sorted list of its
// regular files' relative names and contents. A detached NRRD header's checksum covers the data
// files it names too (volume/nrrd_io.h: nrrdDataFiles, read from the header's folder or from
// `nrrdDataFolder`, as --nrrd-data allows), so a data file changed after an import is noticed.
Result<std::string> checksumPath(const std::string& path, const std::string& nrrdDataFolder = "");
// The checksum of a detached NRRD header's bytes alone: what checksumPath gave before it covered
// the data files, accepted for datasets imported then (verifiedDatasetFiles). nullopt for
// anything else.
Result<std::optional<std::string>> headerOnlyNrrdChecksum(const std::string& path, const std::string& nrrdDataFolder = "");
// The checksum to hold against one recorded earlier: checksumPath, or the header-only checksum
// where that is what was recorded (a detached NRRD imported or exported before).
Result<std::string> checksumAsRecorded(const std::string& path, const std::string& recorded, const std::string& nrrdDataFolder = "");

}  // namespace at::db
