// The shown and the grown volume of a scan (scan_volumes.h).
#include "scan_volumes.h"

#include "render/derived_preset.h"

namespace at::app {

ShownScan leaveOutNonAnatomyForShowing(Dataset& dataset) {
  ShownScan out;
  auto loaded = std::make_unique<Volume>(dataset.volume);
  out.leftOut = render::leaveOutNonAnatomy(dataset.volume, dataset.labels, render::summariseIntensities(dataset.volume));
  if (dataset.volume.voxels != loaded->voxels) out.asLoaded = std::move(loaded);
  return out;
}

}  // namespace at::app
