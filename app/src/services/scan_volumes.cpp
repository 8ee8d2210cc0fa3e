// The shown and the grown volume of a scan (scan_volumes.h).
#include "scan_volumes.h"

#include "shown_dataset.h"

namespace at::app {

ShownScan leaveOutNonAnatomyForShowing(Dataset& dataset) {
  ShownScan out;
  auto loaded = std::make_unique<Volume>(dataset.volume);
  prepareForViewing(dataset);  // as every front end shows it (shown_dataset.h)
  for (std::size_t i = 0; i < loaded->voxels.size(); ++i) out.leftOut += dataset.volume.voxels[i] != loaded->voxels[i];
  if (out.leftOut > 0) out.asLoaded = std::move(loaded);
  return out;
}

}  // namespace at::app
