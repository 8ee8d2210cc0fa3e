// Presets derived from a dataset's own intensities, for any dataset without hand-written presets
// (an import, a study on another dataset): usable looks in every mode, so nothing fails for a
// missing preset file. Shared by the desktop, the `render` command, studies and the course editor.
//
// What is derived (the shipped phantom presets are the model, data/presets/default_*.json):
//   - the scale: CT in Hounsfield units, or plain intensities (MR, an uncalibrated scan) —
//     given by the caller (the dataset's intensity model) or, when unknown, told from the
//     histogram (air at about −1000 and soft tissue near 0: Hounsfield units);
//   - the soft-tissue level T: 40 HU, or the histogram's main mode above the background;
//   - "dense" voxels: at least 150 HU, or above T by four half-widths of its mode; the bone
//     surfaces' opacity band rises from their 10th percentile to a peak at their median and
//     stays a little lower up to their 99th percentile;
//   - the edge-strength ramp from the contrast between T and that peak (a blurred step of height
//     C has a peak gradient of about C/3.5 per voxel);
//   - the WDT's density window: −600…2000 HU, or from the background level to the dense 99th
//     percentile.
// Every mode gets the look of the shipped preset of that mode with these levels put in.
#pragma once

#include <string>

#include "render/preset.h"
#include "volume/grid.h"

namespace at::render {

enum class IntensityScale { Unknown, Hounsfield, Plain };

// The levels a derived preset is built from, computed once per volume (one pass over it).
struct IntensityLevels {
  IntensityScale scale = IntensityScale::Hounsfield;  // never Unknown once summarised
  double background = -1000;  // the lowest populated level (air)
  double tissue = 40;         // T
  double denseLow = 150;      // 10th percentile of the dense voxels
  double densePeak = 400;     // their median
  double denseHigh = 1000;    // their 99th percentile
  double denseShare = 0;      // share of all voxels that are dense
  std::string reason;         // how the scale was decided, for messages ("histogram: air at −1000 …")
};

IntensityLevels summariseIntensities(const Volume& volume, IntensityScale scale = IntensityScale::Unknown);

// The level from which a voxel may be body (volume/body_mask.h): −300 HU for CT (fat is about
// −100), else half way from the background to the soft-tissue level.
double bodyLevel(const IntensityLevels& levels);
// The body (volume/body_mask.h at bodyLevel) joined with every labelled voxel: what is anatomy.
// The rest (a CT table, a headrest) is left out of the context by clearing it to the background
// before the WDT and the rendering. Once per dataset.
Mask anatomyMask(const Volume& volume, const LabelMap& labels, const IntensityLevels& levels);
// Clears the voxels outside anatomyMask to the background level; the number cleared.
std::size_t leaveOutNonAnatomy(Volume& volume, const LabelMap& labels, const IntensityLevels& levels);

// The derived preset of a mode for a structure; id "<structure>_<mode>" and name saying it is
// derived. The highlight is the shipped orange; views are left to the caller's default.
Preset derivedPreset(const IntensityLevels& levels, RenderMode mode, const std::string& structureId);

// The preset to show: the shipped "<structure>_<mode>" when the library has one, else the derived
// one. Errors only for a library folder that cannot be read.
Result<Preset> presetOrDerived(const PresetLibrary& library, const std::string& structureId, RenderMode mode,
                               const IntensityLevels& levels);

}  // namespace at::render
