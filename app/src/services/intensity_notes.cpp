#include "intensity_notes.h"

namespace at::app {

std::optional<std::string> densityWeightsNote(const Dataset& dataset) {
  const IntensityModel& m = dataset.intensity;
  if (m.attenuationLike()) return std::nullopt;
  return "'" + dataset.id + "' is " + m.modality +
         ": its intensities are not attenuation, and density-weighted distances assume CT-like values (bright = dense)";
}

}  // namespace at::app
