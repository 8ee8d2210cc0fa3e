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

// The data files a detached NRRD header names, resolved and in the order loadNrrd reads them, each
// checked to lie in the folder the header may read from (its own, or options.dataFolder) as
// loadNrrd checks it; empty for a NRRD with attached data and for a file that is not a NRRD (does not
// start with "NRRD000"). What a dataset's checksum covers besides the header (db/checksum.h).
Result<std::vector<std::string>> nrrdDataFiles(const std::string& path, const ImageLoadOptions& options = {});
// Whether a detached NRRD header names every data file relative to its own folder, with no ".."
// (no absolute path; not out of the folder, nor through a subfolder and back): what a copy of the
// folder's files elsewhere still reads. True for a NRRD with attached data, for a file that is not a
// NRRD and for a folder (a DICOM series).
Result<bool> nrrdDataFilesRelativeToHeader(const std::string& path);

// Writes an attached-header gzip NRRD (LPS) with optional `key:=value` lines (keys without ":="
// and line breaks); used by tests to make inputs and by the .seg.nrrd writer.
Status writeNrrd(const std::string& path, const FloatVolume& image, ScalarKind storedKind,
                 const std::vector<std::pair<std::string, std::string>>& keyValues = {});

}  // namespace at
