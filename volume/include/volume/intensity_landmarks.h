// Landmarks of a scan's value histogram for plain intensities (no HU calibration: a µCT, an MR, a
// CT stored without its rescale): where the air ends and the soft tissue's level lies. Shared by
// the derived presets (render/derived_preset.h: what is drawn as bone) and the growth defaults
// (segment/growth_settings.h: the "bone only" range), so both read a scan the same way.
#pragma once

#include <cstdint>
#include <vector>

namespace at {

// A histogram with one bin per int16 value: counts[v + 32768] voxels hold the stored value v.
std::vector<std::uint64_t> valueHistogram(const std::vector<std::int16_t>& voxels);

struct SoftTissueLandmarks {
  // The body's threshold: half way from `air` to the mean of all voxels at or above it.
  int bodyThreshold = 0;
  // From that threshold up the air peak's falling tail to where it falls no further (the histogram
  // smoothed over 5 values): above it lie the body's tissues, below it the air and whatever dim
  // levels a scanner leaves around the body (a field-of-view circle at the air's level, a second
  // air level inside it).
  int valley = 0;
  // The commonest value above the valley: the soft tissue where the scan has any (a dry skull's
  // µCT has none: its bone's commonest value then).
  int softTissue = 0;
};

// The landmarks of `histogram` (valueHistogram) above `air`, the scan's low end (e.g. its 0.5th
// or 1st percentile). A scan that is mostly air has more voxels in the air's tail just above the
// body's threshold than at the soft tissue's peak: hence the walk down the tail before the mode.
SoftTissueLandmarks softTissueLandmarks(const std::vector<std::uint64_t>& histogram, int air);

}  // namespace at
