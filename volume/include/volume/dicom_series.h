// DICOM CT series from a folder, through DCMTK (JPEG, JPEG-LS, RLE codecs) and OpenJPEG (JPEG 2000).
// The series is chosen by UID or, if none is given, the one with most slices (the choice is noted).
// Slices are sorted by ImagePositionPatient along the slice normal; spacing comes from positions,
// not SliceThickness; RescaleSlope/Intercept give HU. Uneven spacing, missing slices, gantry tilt
// and mixed sizes are errors naming the folder and the problem.
#pragma once

#include <string>

#include "core/error.h"
#include "volume/image_file.h"

namespace at {

Result<LoadedImage> loadDicomSeries(const std::string& folder, const ImageLoadOptions& options = {});

// True if the file starts with a DICOM preamble ("DICM" at byte 128).
bool looksLikeDicomFile(const std::string& path);

}  // namespace at
