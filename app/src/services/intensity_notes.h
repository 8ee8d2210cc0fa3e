// What a user is told, once per dataset, where the weighted distances on a dataset may mislead:
// its intensities are not attenuation (an MR, by its DICOM modality, or one a course package says
// is an MR), while density-weighted distances assume CT-like values (bright = dense). Both front
// ends show the same line: the command line on stderr, the desktop among its notes.
#pragma once

#include <optional>
#include <string>

#include "volume/structure.h"

namespace at::app {

// "'head' is MR: its intensities are not attenuation, …"; nullopt for CT, µCT and any data whose
// brightness orders densities (no modality, or an attenuation modality).
std::optional<std::string> densityWeightsNote(const Dataset& dataset);

}  // namespace at::app
