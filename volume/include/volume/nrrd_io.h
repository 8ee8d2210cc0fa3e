// NRRD with attached (.nrrd) or detached (.nhdr, or .nrrd with `data file:`) headers: single data
// files and `data file: <format> <min> <max> <step> [<subdim>]` / `LIST` multi-file forms; raw and
// gzip encodings; `space`, `space directions`, `space origin`; 3D Slicer .seg.nrrd segmentations
// (segment names, colours and label values; several layers of overlapping segments merged into
// one label map, the merge noted).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "volume/image_file.h"

namespace at {

Result<LoadedImage> loadNrrd(const std::string& path, const ImageLoadOptions& options = {});

// Writes an attached-header gzip NRRD (LPS) with optional `key:=value` lines (keys without ":="
// and line breaks); used by tests to make inputs and by the .seg.nrrd writer.
Status writeNrrd(const std::string& path, const FloatVolume& image, ScalarKind storedKind,
                 const std::vector<std::pair<std::string, std::string>>& keyValues = {});

}  // namespace at
