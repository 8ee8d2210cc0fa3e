// Grow from seeds with per-label value ranges (the seeds file's "grow_range"): a label with a range
// ("bone only") keeps only voxels whose value lies in it, and takes them by a growth that cannot
// leave the range, so a thin bone is not padded with the soft tissue and air between its plates
// and its neighbours. Labels without a range grow as usual.
//
// With A the ordinary growth of all seeds, and R_r the growth of all seeds limited to range r
// (GrowthParams::limitRange: it never enters nor crosses a voxel outside r; every label's seeds
// compete in it, background included), each voxel v takes
//   R_r(v)  for the first range r (in the labels' order) whose growth gives v a label having range
//           r, where v's value lies in r;
//   A(v)    otherwise, where A(v) is a label without a range;
//   0       otherwise (what A gave a ranged label outside its range is background).
// So a ranged label's voxels are always inside its range, and an unranged label loses voxels only
// to a ranged label whose range holds them. One more growth (CPU) per distinct range.
// The segment editor's live growth and `anatomy-tutor segment --seeds` both apply it (RangedGrowth).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "core/error.h"
#include "segment/growth_settings.h"
#include "segment/seeds.h"
#include "volume/grid.h"
#include "volume/intensity.h"
#include "wdt/label_growth.h"

namespace at::segment {

struct LabelValueRange {
  std::uint16_t label = 0;
  std::array<double, 2> values{};  // the dataset's values (HU or intensities), low < high
};

// The seeds' per-label ranges, "bone" resolved to `boneRangeValues` (GrowthDefaults), in the
// labels' order; empty when no label has one.
std::vector<LabelValueRange> labelRangesOf(const SeedSet& seeds, const std::array<double, 2>& boneRangeValues);

// Per-label ranges as a growth takes them: the ranges (labelRangesOf) and the intensity model that
// maps their values to the volume's stored values. No range: the ordinary growth alone.
struct LabelRanges {
  IntensityModel intensity;
  std::vector<LabelValueRange> ranges;
  bool empty() const { return ranges.empty(); }
};

// The rule above, kept between calls: each distinct range's limited growth is kept with the params
// and volume it was made for, so growing again after seed edits is incremental (LabelGrowth::update:
// only what the changed seeds affect), as the ordinary growth is in the segment editor; another
// volume or params start it afresh. The segment editor (LabelEditor::computeGrowth) and
// `anatomy-tutor segment` both grow through it, so the desktop and the command line give the same
// labels from the same seeds file. Not thread-safe: one apply at a time.
class RangedGrowth {
 public:
  RangedGrowth();
  ~RangedGrowth();
  RangedGrowth(RangedGrowth&&) noexcept;
  RangedGrowth& operator=(RangedGrowth&&) noexcept;

  // The rule above. `unranged` is A (the ordinary growth's labels on the volume's grid), `params`
  // the ordinary growth's (their own range limit, if any, is replaced by each label range).
  // `control.cancel` stops a limited growth between rounds: then `stats`->cancelled is set and the
  // labels returned are not the rule's (commit nothing; the next apply finishes the work left).
  // `stats` (optional) adds the limited growths' brick visits, rounds and compute time. Errors: a
  // grid mismatch, a range that is not low < high, a ranged label 0, the growth's errors.
  // `unrangedGrowth` (optional): the ordinary growth, made on this volume with `params`; a limited
  // growth made afresh copies its values from it (or from the previous range's growth) instead of
  // smoothing the volume again (LabelGrowth::create with sameValues; the labels are the same).
  Result<LabelMap> apply(const Volume& volume, const LabelMap& unranged, const std::vector<GrowthSeed>& seeds,
                         const GrowthParams& params, const LabelRanges& ranges, const WdtControl& control = {},
                         GrowthStats* stats = nullptr, const LabelGrowth* unrangedGrowth = nullptr);

 private:
  struct Kept;
  std::vector<std::unique_ptr<Kept>> kept_;
};

// One apply of a fresh RangedGrowth (nothing kept).
Result<LabelMap> growWithLabelRanges(const Volume& volume, const IntensityModel& intensity, const LabelMap& unranged,
                                     const std::vector<GrowthSeed>& seeds, const GrowthParams& params,
                                     const std::vector<LabelValueRange>& ranges);

}  // namespace at::segment
