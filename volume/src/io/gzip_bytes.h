// gzip compression of a buffer in memory, for the writers (NRRD, NIfTI .nii.gz) that build their
// file in memory and hand it to AtomicFile in one piece.
#pragma once

#include <string>

#include "core/error.h"

namespace at {

// `plain` as one gzip member; `path` names the file in errors.
Result<std::string> gzipBytes(const std::string& path, const std::string& plain);

}  // namespace at
