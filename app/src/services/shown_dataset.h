// A dataset as every front end shows it (render command, desktop, terminal pictures, default
// views, question checks): the objects outside the body — a CT table, a headrest — cleared to the
// background (render::leaveOutNonAnatomy) before any field, unit or picture reads the volume, so
// that one scan gives one picture whichever front end draws it.
#pragma once

#include "core/error.h"
#include "dataset_resolver.h"
#include "render/derived_preset.h"
#include "volume/structure.h"

namespace at::app {

// Clears what is not anatomy in place; returns the intensity levels of the scan as it was opened
// (what derived presets are built from).
render::IntensityLevels prepareForViewing(Dataset& dataset);

// openNamedDataset, then prepareForViewing.
struct ShownDataset {
  Dataset dataset;
  render::IntensityLevels levels;
};
Result<ShownDataset> openDatasetForViewing(const DatasetRequest& request);

}  // namespace at::app
