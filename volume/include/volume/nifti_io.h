// NIfTI-1 and NIfTI-2 (.nii, .nii.gz) through niftilib. The sform (preferred when set) or qform
// gives the patient frame; NIfTI's RAS+ world is converted to LPS.
#pragma once

#include <string>

#include "core/error.h"
#include "volume/grid.h"
#include "volume/image_file.h"

namespace at {

Result<LoadedImage> loadNifti(const std::string& path, const ImageLoadOptions& options = {});

// Writes a float32 image with its geometry (sform and qform set from the LPS geometry).
Status writeNiftiFloat(const std::string& path, const FloatVolume& image);
// Writes labels as uint16 (used by tests and export).
Status writeNiftiLabels(const std::string& path, const LabelMap& labels);

}  // namespace at
