// SegmentController: the growth's settings (defaults from the data, the user's changes previewed by
// growing again) and seeds files (save the painted seeds, load a file's).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <map>

#include "core/strings.h"
#include "segment/seeds.h"
#include "segment_editor/segment_controller.h"

namespace at::app {

GrowthParams SegmentController::growthParams() const {
  GrowthParams p = defaults_.params;
  p.baseCost = float(segment::basePerMm(settings_.basePerVoxel, defaults_.voxelMm));
  if (dataset_) {
    const auto stored = segment::storedWindow(dataset_->intensity, settings_.window);
    p.windowMin = stored[0];
    p.windowMax = stored[1];
  }
  p.smoothingVoxels = float(settings_.smoothingVoxels);
  if (dataset_ && settings_.limitRange) p = segment::withRangeLimit(p, dataset_->intensity, settings_.range);
  return p;
}

Status SegmentController::setGrowthSettings(const GrowthSettings& settings) {
  if (auto ok = requireDataset(); !ok) return ok;
  if (!std::isfinite(settings.basePerVoxel) || !(settings.basePerVoxel > 0))
    return fail("segment editor: the base per voxel must be > 0, got " + std::to_string(settings.basePerVoxel));
  if (!(settings.window[1] > settings.window[0]))
    return fail("segment editor: the growth window must have high > low, got " + std::to_string(settings.window[0]) +
                " … " + std::to_string(settings.window[1]));
  if (!(settings.smoothingVoxels >= 0 && settings.smoothingVoxels <= 8))
    return fail("segment editor: smoothing must be 0 … 8 voxels, got " + std::to_string(settings.smoothingVoxels));
  if (settings.limitRange && !(settings.range[1] >= settings.range[0]))
    return fail("segment editor: the grow-only range must have high >= low, got " + std::to_string(settings.range[0]) +
                " … " + std::to_string(settings.range[1]));
  const GrowthSettings before = settings_;
  settings_ = settings;
  if (auto ok = validateGrowthParams(growthParams()); !ok) {
    settings_ = before;
    return ok;
  }
  events_({{"event", "segment_growth_settings"},
           {"base_per_voxel", settings_.basePerVoxel},
           {"window", {settings_.window[0], settings_.window[1]}},
           {"smoothing_voxels", settings_.smoothingVoxels},
           {"range", settings_.limitRange ? nlohmann::json{settings_.range[0], settings_.range[1]} : nlohmann::json()}});
  // The live preview: a growth seen on screen is grown again with the new settings.
  if (grownOnce_ && seedsPerLabel().size() >= 2) return grow();
  return {};
}

Status SegmentController::setLabelGrowRange(std::uint16_t label, std::optional<LabelGrowRange> range) {
  if (auto ok = requireDataset(); !ok) return ok;
  if (label == 0) return fail("segment editor: the background (label 0) cannot have a grow range");
  if (std::none_of(structures().begin(), structures().end(), [&](const Structure& s) { return s.label == label; }))
    return fail(ErrorKind::NotFound, "segment editor: no label " + std::to_string(label));
  if (range && !range->bone && !(range->values && (*range->values)[0] < (*range->values)[1]))
    return fail("segment editor: a label's grow range must be \"bone\" or low < high" +
                (range->values ? ", got " + std::to_string((*range->values)[0]) + " … " + std::to_string((*range->values)[1])
                               : std::string()));
  const auto at = std::find_if(growRanges_.begin(), growRanges_.end(), [&](const auto& r) { return r.first == label; });
  if (!range) {
    if (at != growRanges_.end()) growRanges_.erase(at);
  } else if (at != growRanges_.end()) {
    at->second = *range;
  } else {
    growRanges_.push_back({label, *range});
  }
  nlohmann::json values = range && !range->bone ? nlohmann::json{(*range->values)[0], (*range->values)[1]} : nlohmann::json();
  events_({{"event", "segment_label_range"}, {"label", label}, {"range", values}, {"bone", range && range->bone}});
  if (grownOnce_ && seedsPerLabel().size() >= 2) return grow();  // the live preview
  return {};
}

std::optional<SegmentController::LabelGrowRange> SegmentController::labelGrowRange(std::uint16_t label) const {
  for (const auto& [l, range] : growRanges_)
    if (l == label) return range;
  return std::nullopt;
}

segment::LabelRanges SegmentController::labelRanges() const {
  segment::LabelRanges out;
  if (!dataset_) return out;
  out.intensity = dataset_->intensity;
  for (const auto& [label, range] : growRanges_)
    out.ranges.push_back({label, range.bone ? defaults_.boneRangeValues : *range.values});
  return out;
}

void SegmentController::resetGrowthSettings() {
  (void)setGrowthSettings({segment::basePerVoxelOf(defaults_.params.baseCost, defaults_.voxelMm), defaults_.windowValues,
                           defaults_.params.smoothingVoxels, false, defaults_.boneRangeValues});
}

Status SegmentController::saveSeeds(const std::string& path) const {
  if (auto ok = requireDataset(); !ok) return ok;
  if (seeds_.empty()) return fail("save seeds: no seed is painted");
  segment::SeedSet set;
  std::map<std::uint16_t, std::size_t> labelIndex;
  // The seeded labels by value, except that the ranged ones among them keep the order of their
  // ranges (the rule's order: ranged_growth.h), each in the slot of a ranged label.
  std::vector<std::uint16_t> order;
  for (const auto& [label, count] : seedsPerLabel()) order.push_back(label);
  std::vector<std::uint16_t> rangedOrder;
  for (const auto& [label, range] : growRanges_)
    if (std::find(order.begin(), order.end(), label) != order.end()) rangedOrder.push_back(label);
  std::size_t nextRanged = 0;
  for (std::uint16_t& label : order)
    if (labelGrowRange(label)) label = rangedOrder[nextRanged++];
  for (const std::uint16_t label : order) {
    segment::SeedLabel l;
    l.value = label;
    if (label == 0) {
      l.name = "background";
    } else {
      const auto found = std::find_if(structures().begin(), structures().end(),
                                      [&](const Structure& s) { return s.label == label; });
      l.name = found != structures().end() ? found->id : "label_" + std::to_string(label);
      if (found != structures().end()) l.colour = found->colour;
      if (const auto range = labelGrowRange(label)) {
        l.growRange = range->values;
        l.growRangeBone = range->bone;
      }
    }
    labelIndex[label] = set.labels.size();
    set.labels.push_back(l);
  }
  const Geometry& g = dataset_->volume.geometry;
  const Dims d = g.dims;
  // One stroke of radius 0 per run of seed voxels of one label along a row (i consecutive, j and k
  // fixed): from the first voxel's centre to the last's. Rasterised, its samples (every half of the
  // smallest spacing) seed exactly the run's voxels, so the file reloads to the same seeds while
  // a painted region is written as rows, not as one dot per voxel (a skull's 873 k seed voxels
  // as dots exceeded the seeds reader's 64 MiB limit).
  const auto centre = [&](std::size_t index) {
    return g.indexToPatient({double(index % std::size_t(d.x)), double(index / std::size_t(d.x) % std::size_t(d.y)),
                             double(index / (std::size_t(d.x) * std::size_t(d.y)))});
  };
  for (auto it = seeds_.begin(); it != seeds_.end();) {
    const std::size_t first = it->first;
    const std::uint16_t label = it->second;
    std::size_t last = first;
    auto next = std::next(it);
    while (next != seeds_.end() && next->first == last + 1 && next->second == label && next->first % std::size_t(d.x) != 0)
      last = next->first, ++next;
    segment::SeedStroke run;
    run.label = labelIndex.at(label);
    run.pointsMm.push_back(centre(first));
    if (last != first) run.pointsMm.push_back(centre(last));
    set.strokes.push_back(std::move(run));
    it = next;
  }
  set.grow.weight = "gradient";
  set.grow.window = settings_.window;
  set.grow.base = double(growthParams().baseCost);
  if (settings_.limitRange) set.grow.range = settings_.range;
  set.grow.smoothing = settings_.smoothingVoxels;
  std::FILE* file = std::fopen(path.c_str(), "wb");
  if (!file) return fail(ErrorKind::Io, "save seeds: cannot write " + path);
  const std::string text = segment::seedsToJson(set);
  const bool written = std::fwrite(text.data(), 1, text.size(), file) == text.size();
  const bool closed = std::fclose(file) == 0;
  if (!written || !closed) return fail(ErrorKind::Io, "save seeds: writing " + path + " failed");
  return {};
}

Result<std::size_t> SegmentController::loadSeeds(const std::string& path) {
  if (auto ok = requireDataset(); !ok) return tl::unexpected(ok.error());
  auto set = segment::loadSeeds(path);
  if (!set) return tl::unexpected(set.error());
  auto raster = segment::rasteriseSeeds(*set, dataset_->volume.geometry);
  if (!raster) return tl::unexpected(withContext(path, raster.error()));
  // The file's labels by name: the background, a structure the editor has, or a new structure.
  std::vector<std::uint16_t> editorLabel;
  for (const segment::SeedLabel& l : set->labels) {
    if (l.value == 0) {
      editorLabel.push_back(0);
      continue;
    }
    auto found = labelNamed(l.name);
    if (!found) found = addLabel(l.name);
    if (!found) return tl::unexpected(withContext(path, found.error()));
    editorLabel.push_back(*found);
  }
  std::map<std::uint16_t, std::uint16_t> byValue;  // file label value → editor label
  for (std::size_t i = 0; i < set->labels.size(); ++i) byValue[set->labels[i].value] = editorLabel[i];
  seeds_.clear();
  for (const GrowthSeed& s : raster->seeds) seeds_[s.index] = byValue.at(s.label);
  growRanges_.clear();
  for (std::size_t i = 0; i < set->labels.size(); ++i)
    if (set->labels[i].hasGrowRange())
      growRanges_.push_back({editorLabel[i], {set->labels[i].growRange, set->labels[i].growRangeBone}});
  GrowthSettings settings = settings_;
  if (set->grow.window) settings.window = *set->grow.window;
  if (set->grow.base) settings.basePerVoxel = segment::basePerVoxelOf(*set->grow.base, defaults_.voxelMm);
  settings.limitRange = set->grow.range.has_value();
  if (set->grow.range) settings.range = *set->grow.range;
  if (set->grow.smoothing) settings.smoothingVoxels = *set->grow.smoothing;
  if (auto ok = setGrowthSettings(settings); !ok) return tl::unexpected(withContext(path, ok.error()));
  ++revision_;
  status_ = "seeds loaded from " + path + ": " + std::to_string(seeds_.size()) + " voxels";
  if (!growRanges_.empty())
    status_ += "; " + std::to_string(growRanges_.size()) + " labels grow only in their range";
  events_({{"event", "segment_seeds_loaded"}, {"path", path}, {"seeds", seeds_.size()}, {"labels_with_grow_range", growRanges_.size()}});
  return seeds_.size();
}

}  // namespace at::app
