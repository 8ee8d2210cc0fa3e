// The two volumes of an opened scan: the one the front ends show and the one grow from seeds reads.
//
// Pictures leave out what is not anatomy (render::leaveOutNonAnatomy: a CT table, a headrest,
// cleared to the background level) so that it never renders as context. Grow from seeds, its
// data-derived defaults (segment/growth_settings.h: the step noise, hence the base, is measured
// over every voxel) and the threshold tools read the voxels as loaded instead, in every front end:
// `anatomy-tutor segment` grows on the scan as it opens it, and the desktop's segment editor on the
// volume kept here, so one seeds file grows the same labels in both.
#pragma once

#include <cstddef>
#include <memory>

#include "volume/structure.h"

namespace at::app {

struct ShownScan {
  std::size_t leftOut = 0;                 // voxels cleared in the dataset's volume for showing
  std::unique_ptr<const Volume> asLoaded;  // the volume before clearing; null when nothing was cleared
  // The volume grow from seeds reads for `shown` (the dataset this was made from): as loaded.
  const Volume& growthVolume(const Dataset& shown) const { return asLoaded ? *asLoaded : shown.volume; }
};

// Leaves out the non-anatomy of `dataset` for showing (before anything reads its volume) and keeps
// the volume as loaded where that changed a voxel.
ShownScan leaveOutNonAnatomyForShowing(Dataset& dataset);

}  // namespace at::app
