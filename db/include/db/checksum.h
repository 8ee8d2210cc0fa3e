// Content checksums for the files a dataset references (the database stores paths + checksums,
// never pixels), so a moved or modified file is noticed.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "core/error.h"
#include "core/sha256.h"

namespace at::db {

// SHA-256 of a byte string, as 64 lowercase hex digits (core/sha256.h).
using at::sha256Hex;

// "sha256:<hex>" of a file's bytes, or for a folder (a DICOM series) of the sorted list of its
// regular files' relative names and contents.
Result<std::string> checksumPath(const std::string& path);

}  // namespace at::db
