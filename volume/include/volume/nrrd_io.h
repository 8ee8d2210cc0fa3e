// NRRD with attached (.nrrd) or detached (.nhdr, or .nrrd with `data file:`) headers: single data
// files and `data file: <format> <min> <max> <step> [<subdim>]` / `LIST` multi-file forms; raw and
// gzip encodings; `space`, `space directions`, `space origin`; 3D Slicer .seg.nrrd segment names.
#pragma once

#include <string>

#include "core/error.h"
#include "volume/image_file.h"

namespace at {

Result<LoadedImage> loadNrrd(const std::string& path, const ImageLoadOptions& options = {});

// Writes an attached-header gzip NRRD (LPS); used by tests to make inputs.
Status writeNrrd(const std::string& path, const FloatVolume& image, ScalarKind storedKind);

}  // namespace at
