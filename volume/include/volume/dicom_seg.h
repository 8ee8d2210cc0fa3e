// DICOM SEG (Segmentation Storage, binary) through DCMTK's dcmseg. Segments become labels
// (segment number = label value; overlapping segments: the higher number wins, noted) on the
// segmentation's own frame geometry; resample onto a CT grid with resampleLabelsNearest.
#pragma once

#include <string>

#include "core/error.h"
#include "volume/image_file.h"

namespace at {

// `image` holds label values; `segments` their names. Of `options`, the memory limit applies.
Result<LoadedImage> loadDicomSeg(const std::string& path, const ImageLoadOptions& options = {});

// True if the file is a DICOM Segmentation Storage object.
bool isDicomSegFile(const std::string& path);

}  // namespace at
