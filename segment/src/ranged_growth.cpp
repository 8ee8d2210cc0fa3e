// Growth with per-label value ranges: the ordinary growth, then one range-limited growth per
// distinct range, combined by the rule in ranged_growth.h.
#include "segment/ranged_growth.h"

#include <algorithm>
#include <string>

namespace at::segment {

std::vector<LabelValueRange> labelRangesOf(const SeedSet& seeds, const std::array<double, 2>& boneRangeValues) {
  std::vector<LabelValueRange> out;
  for (const SeedLabel& l : seeds.labels) {
    if (l.growRangeBone) out.push_back({l.value, boneRangeValues});
    else if (l.growRange) out.push_back({l.value, *l.growRange});
  }
  return out;
}

struct RangedGrowth::Kept {
  std::array<double, 2> values{};
  const Volume* volume = nullptr;
  Dims dims;
  GrowthParams params;
  LabelGrowth growth;
};

RangedGrowth::RangedGrowth() = default;
RangedGrowth::~RangedGrowth() = default;
RangedGrowth::RangedGrowth(RangedGrowth&&) noexcept = default;
RangedGrowth& RangedGrowth::operator=(RangedGrowth&&) noexcept = default;

Result<LabelMap> RangedGrowth::apply(const Volume& volume, const LabelMap& unranged, const std::vector<GrowthSeed>& seeds,
                                     const GrowthParams& params, const LabelRanges& labelRanges, const WdtControl& control,
                                     GrowthStats* stats, const LabelGrowth* unrangedGrowth) {
  const std::vector<LabelValueRange>& ranges = labelRanges.ranges;
  if (unranged.voxels.size() != volume.voxels.size())
    return fail("ranged growth: the labels' grid (" + std::to_string(unranged.voxels.size()) + " voxels) is not the volume's (" +
                std::to_string(volume.voxels.size()) + ")");
  std::vector<std::uint8_t> isRanged(65536, 0);
  for (const LabelValueRange& r : ranges) {
    if (r.label == 0) return fail("ranged growth: the background (label 0) cannot have a range");
    if (!(r.values[0] < r.values[1]))
      return fail("ranged growth: label " + std::to_string(r.label) + ": range " + std::to_string(r.values[0]) + " … " +
                  std::to_string(r.values[1]) + " is not low < high");
    isRanged[r.label] = 1;
  }
  LabelMap out = unranged;
  for (std::uint16_t& v : out.voxels)
    if (isRanged[v]) v = 0;
  if (ranges.empty()) return out;

  std::vector<std::uint8_t> decided(volume.voxels.size(), 0);
  std::vector<std::array<double, 2>> done;
  std::vector<std::unique_ptr<Kept>> used;  // this apply's ranges' growths, kept for the next
  for (const LabelValueRange& first : ranges) {
    if (std::find(done.begin(), done.end(), first.values) != done.end()) continue;
    done.push_back(first.values);
    std::vector<std::uint8_t> inThisRange(65536, 0);
    for (const LabelValueRange& r : ranges)
      if (r.values == first.values) inThisRange[r.label] = 1;
    GrowthParams limited = withRangeLimit(params, labelRanges.intensity, first.values);
    limited.backend = WdtBackend::Cpu;  // limited growth runs on the CPU (label_growth.h)
    // The kept growth of this range, if it still fits the volume and params; else a fresh one.
    std::unique_ptr<Kept> kept;
    for (auto& k : kept_)
      if (k && k->values == first.values && k->volume == &volume && k->dims == volume.dims() && k->params == limited)
        kept = std::move(k);
    if (!kept) {
      // The values are the ordinary growth's (the same window and smoothing): copied, not smoothed again.
      const LabelGrowth* sameValues = used.empty() ? unrangedGrowth : &used.back()->growth;
      auto growth = LabelGrowth::create(volume, limited, sameValues);
      if (!growth) return tl::unexpected(growth.error());
      kept.reset(new Kept{first.values, &volume, volume.dims(), limited, std::move(*growth)});
    }
    auto grownStats = kept->growth.update(seeds, control);
    if (!grownStats) return tl::unexpected(grownStats.error());
    if (stats) {
      stats->brickVisits += grownStats->brickVisits;
      stats->rounds += grownStats->rounds;
      stats->msCompute += grownStats->msCompute;
      stats->msTotal += grownStats->msTotal;
    }
    const bool cancelled = grownStats->cancelled;
    const std::vector<std::uint16_t>& grown = kept->growth.labels().voxels;
    used.push_back(std::move(kept));
    if (cancelled) {
      if (stats) stats->cancelled = true, stats->converged = false;
      for (auto& k : kept_)
        if (k) used.push_back(std::move(k));
      kept_ = std::move(used);
      return out;
    }
    for (std::size_t i = 0; i < grown.size(); ++i) {
      if (decided[i] || !inThisRange[grown[i]]) continue;
      const float value = float(volume.voxels[i]);
      if (value < limited.rangeMin || value > limited.rangeMax) continue;  // a seed painted outside
      out.voxels[i] = grown[i];
      decided[i] = 1;
    }
  }
  kept_ = std::move(used);  // ranges no longer asked for are dropped
  return out;
}

Result<LabelMap> growWithLabelRanges(const Volume& volume, const IntensityModel& intensity, const LabelMap& unranged,
                                     const std::vector<GrowthSeed>& seeds, const GrowthParams& params,
                                     const std::vector<LabelValueRange>& ranges) {
  RangedGrowth growth;
  return growth.apply(volume, unranged, seeds, params, LabelRanges{intensity, ranges});
}

}  // namespace at::segment
