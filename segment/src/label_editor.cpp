// LabelEditor: the tools, each turned into a list of label changes that is applied and recorded.
#include "segment/label_editor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>

#include "core/strings.h"
#include "segment/distance_map.h"
#include "volume/mask.h"

namespace at::segment {

namespace {

using Changes = std::vector<std::pair<std::size_t, std::uint16_t>>;

std::string mm(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g mm", v);
  return buf;
}

std::string count(std::size_t n) { return std::to_string(n) + (n == 1 ? " voxel" : " voxels"); }

// The voxel nearest to a point in LPS mm, or an error naming the point and the grid.
Result<std::size_t> voxelAt(const Geometry& g, const Vec3& pointMm, const char* what) {
  const Vec3 ijk = g.patientToIndex(pointMm);
  const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
  if (!g.dims.contains(i, j, k)) {
    char buf[160];
    std::snprintf(buf, sizeof buf, "%s (%.1f, %.1f, %.1f) mm lies outside the %s grid", what, pointMm[0], pointMm[1],
                  pointMm[2], g.dims.toString().c_str());
    return fail(buf);
  }
  return g.dims.index(i, j, k);
}

// The 6-connected region of `mask` that holds voxel `start` (which must be set).
Mask connectedRegion(const Mask& mask, std::size_t start) {
  const Dims d = mask.dims();
  Mask region(mask.geometry, 0);
  std::deque<std::size_t> queue{start};
  region.voxels[start] = 1;
  const std::size_t nx = std::size_t(d.x), nxy = nx * std::size_t(d.y);
  while (!queue.empty()) {
    const std::size_t v = queue.front();
    queue.pop_front();
    const int x = int(v % nx), y = int(v / nx % std::size_t(d.y)), z = int(v / nxy);
    const int next[6][3] = {{x - 1, y, z}, {x + 1, y, z}, {x, y - 1, z}, {x, y + 1, z}, {x, y, z - 1}, {x, y, z + 1}};
    for (const auto& n : next) {
      if (!d.contains(n[0], n[1], n[2])) continue;
      const std::size_t w = d.index(n[0], n[1], n[2]);
      if (mask.voxels[w] && !region.voxels[w]) {
        region.voxels[w] = 1;
        queue.push_back(w);
      }
    }
  }
  return region;
}

Mask maskOf(const LabelMap& labels, std::uint16_t label) { return structureMask(labels, label); }

// The brush's ball: the voxels whose centres lie within radiusMm of centreMm (in mm, so on an
// anisotropic grid it spans more voxels along the finer axes), and always the voxel under the
// centre; sorted by index. Only the ball's bounding box is visited. Errors: a centre outside the grid.
Result<std::vector<std::size_t>> ballAround(const Geometry& g, const Vec3& centreMm, double radiusMm, const char* what) {
  auto centre = voxelAt(g, centreMm, what);
  if (!centre) return tl::unexpected(centre.error());
  const Vec3 c = g.patientToIndex(centreMm);
  int reach[3];
  for (int a = 0; a < 3; ++a) reach[a] = int(std::ceil(radiusMm / g.spacingMm[std::size_t(a)])) + 1;
  std::vector<std::size_t> ball{*centre};
  for (int k = int(std::lround(c[2])) - reach[2]; k <= int(std::lround(c[2])) + reach[2]; ++k)
    for (int j = int(std::lround(c[1])) - reach[1]; j <= int(std::lround(c[1])) + reach[1]; ++j)
      for (int i = int(std::lround(c[0])) - reach[0]; i <= int(std::lround(c[0])) + reach[0]; ++i)
        if (g.dims.contains(i, j, k) && norm(g.indexToPatient({double(i), double(j), double(k)}) - centreMm) <= radiusMm)
          ball.push_back(g.dims.index(i, j, k));
  std::sort(ball.begin(), ball.end());
  ball.erase(std::unique(ball.begin(), ball.end()), ball.end());
  return ball;
}

}  // namespace

struct LabelEditor::Growth {
  const Volume* volume = nullptr;
  Dims dims;
  GrowthParams params;
  std::optional<LabelGrowth> growth;
  RangedGrowth ranged;                 // per-label ranges' limited growths (ranged_growth.h)
  std::optional<LabelMap> rangedLabels;  // the last computeGrowth's labels when it had ranges
};

LabelEditor::LabelEditor(LabelMap labels, std::vector<Structure> structures)
    : labels_(std::move(labels)), structures_(std::move(structures)) {}
LabelEditor::~LabelEditor() = default;
LabelEditor::LabelEditor(LabelEditor&&) noexcept = default;
LabelEditor& LabelEditor::operator=(LabelEditor&&) noexcept = default;

const Structure* LabelEditor::find(std::uint16_t label) const {
  for (const Structure& s : structures_)
    if (s.label == label) return &s;
  return nullptr;
}

Status LabelEditor::requireStructure(std::uint16_t label) const {
  if (find(label)) return {};
  return fail(ErrorKind::NotFound, "there is no structure with label " + std::to_string(label) +
                                       " (add it first; labels in use: " + std::to_string(structures_.size()) + ")");
}

EditSummary LabelEditor::commit(const std::string& description, const Changes& changes,
                                std::optional<std::vector<Structure>> structuresBefore) {
  std::vector<LabelChange> delta;
  delta.reserve(changes.size());
  for (const auto& [index, value] : changes) {
    if (labels_.voxels[index] == value) continue;
    delta.push_back({index, labels_.voxels[index], value});
    labels_.voxels[index] = value;
  }
  EditSummary summary;
  summary.changed = delta.size();
  summary.description = description + ": " + count(delta.size());
  if (structuresBefore && stroke_) endStroke();
  if (!delta.empty() || structuresBefore) {
    if (stroke_ && stroke_->edits++ == 0) stroke_->tool = description;
    LabelHistory::Entry entry;
    entry.description = summary.description;
    entry.delta = LabelDelta::fromSortedChanges(delta);
    if (structuresBefore) {
      entry.structuresBefore = std::move(structuresBefore);
      entry.structuresAfter = structures_;
    }
    history_.record(std::move(entry));
  }
  summary.historyBytes = history_.bytes();
  return summary;
}

EditSummary LabelEditor::commitMask(const std::string& description, const Mask& mask, std::uint16_t value,
                                    std::optional<std::uint16_t> onlyWhere) {
  Changes changes;
  for (std::size_t i = 0; i < mask.voxels.size(); ++i)
    if (mask.voxels[i] && (!onlyWhere || labels_.voxels[i] == *onlyWhere)) changes.push_back({i, value});
  return commit(description, changes);
}

Result<std::uint16_t> LabelEditor::addStructure(const std::string& name, std::optional<std::array<float, 3>> colour) {
  if (name.empty()) return fail("a structure needs a name");
  for (const Structure& s : structures_)
    if (s.displayName == name || s.id == name) return fail(ErrorKind::Conflict, "a structure named '" + name + "' exists already");
  std::uint16_t label = 1;
  for (const Structure& s : structures_) label = std::max<std::uint16_t>(label, std::uint16_t(s.label + 1));
  for (std::uint16_t v : labels_.voxels) label = std::max<std::uint16_t>(label, std::uint16_t(v + 1));
  if (label == 0 || label == 0xFFFF) return fail("no label value left for a new structure");
  const std::vector<Structure> before = structures_;
  Structure s;
  s.label = label;
  s.displayName = name;
  s.id = str::identifier(name);
  s.colour = colour.value_or(paletteColour(label));
  structures_.push_back(s);
  commit("add structure '" + name + "'", {}, before);
  return label;
}

Status LabelEditor::renameStructure(std::uint16_t label, const std::string& name) {
  if (auto ok = requireStructure(label); !ok) return ok;
  if (name.empty()) return fail("a structure needs a name");
  for (const Structure& s : structures_)
    if (s.label != label && (s.displayName == name || s.id == name))
      return fail(ErrorKind::Conflict, "a structure named '" + name + "' exists already");
  const std::vector<Structure> before = structures_;
  for (Structure& s : structures_)
    if (s.label == label) s.displayName = name;
  commit("rename structure " + std::to_string(label) + " to '" + name + "'", {}, before);
  return {};
}

Status LabelEditor::setColour(std::uint16_t label, std::array<float, 3> colour) {
  if (auto ok = requireStructure(label); !ok) return ok;
  for (float c : colour)
    if (!(c >= 0 && c <= 1)) return fail("colour channels must lie in 0 … 1");
  const std::vector<Structure> before = structures_;
  for (Structure& s : structures_)
    if (s.label == label) s.colour = colour;
  commit("colour structure " + std::to_string(label), {}, before);
  return {};
}

Status LabelEditor::setSystem(std::uint16_t label, const std::string& system) {
  if (auto ok = requireStructure(label); !ok) return ok;
  const std::vector<Structure> before = structures_;
  std::string trimmed = system;
  trimmed.erase(0, trimmed.find_first_not_of(" \t"));
  trimmed.erase(trimmed.find_last_not_of(" \t") + 1);
  for (Structure& s : structures_)
    if (s.label == label) s.system = trimmed;
  commit("system of structure " + std::to_string(label) + ": '" + trimmed + "'", {}, before);
  return {};
}

Result<EditSummary> LabelEditor::deleteStructure(std::uint16_t label) {
  if (auto ok = requireStructure(label); !ok) return tl::unexpected(ok.error());
  const std::vector<Structure> before = structures_;
  const std::string name = find(label)->displayName;
  structures_.erase(std::remove_if(structures_.begin(), structures_.end(), [&](const Structure& s) { return s.label == label; }),
                    structures_.end());
  Changes changes;
  for (std::size_t i = 0; i < labels_.voxels.size(); ++i)
    if (labels_.voxels[i] == label) changes.push_back({i, 0});
  return commit("delete structure '" + name + "'", changes, before);
}

Result<EditSummary> LabelEditor::paint(const Vec3& centreMm, double radiusMm, std::uint16_t label) {
  if (auto ok = requireStructure(label); !ok) return tl::unexpected(ok.error());
  if (!(radiusMm >= 0)) return fail("the brush radius must be >= 0 mm");
  auto ball = ballAround(labels_.geometry, centreMm, radiusMm, "the brush centre");
  if (!ball) return tl::unexpected(ball.error());
  Changes changes;
  changes.reserve(ball->size());
  for (std::size_t v : *ball) changes.push_back({v, label});
  return commit("paint '" + find(label)->displayName + "' (" + mm(radiusMm) + ")", changes);
}

Result<EditSummary> LabelEditor::erase(const Vec3& centreMm, double radiusMm, std::optional<std::uint16_t> only) {
  if (!(radiusMm >= 0)) return fail("the eraser radius must be >= 0 mm");
  auto ball = ballAround(labels_.geometry, centreMm, radiusMm, "the eraser centre");
  if (!ball) return tl::unexpected(ball.error());
  Changes changes;
  for (std::size_t v : *ball)
    if (labels_.voxels[v] != 0 && (!only || labels_.voxels[v] == *only)) changes.push_back({v, 0});
  return commit("erase (" + mm(radiusMm) + ")", changes);
}

Result<EditSummary> LabelEditor::thresholdIsland(const Volume& volume, const IntensityModel& intensity,
                                                 const Vec3& pointMm, double low, double high, std::uint16_t label,
                                                 const ThresholdOptions& options) {
  if (auto ok = requireStructure(label); !ok) return tl::unexpected(ok.error());
  if (!volume.geometry.sameGridAs(labels_.geometry))
    return fail("threshold island: the volume is not on the label map's grid");
  if (!(low <= high)) return fail("threshold island: the range needs low <= high");
  auto start = voxelAt(labels_.geometry, pointMm, "the point");
  if (!start) return tl::unexpected(start.error());
  Mask inRange(labels_.geometry, 0);
  for (std::size_t i = 0; i < inRange.voxels.size(); ++i) {
    const double v = intensity.valueOf(volume.voxels[i]);
    const bool free = options.overwrite || labels_.voxels[i] == 0 || labels_.voxels[i] == label;
    inRange.voxels[i] = v >= low && v <= high && free;
  }
  const double here = intensity.valueOf(volume.voxels[*start]);
  if (!inRange.voxels[*start]) {
    char buf[200];
    std::snprintf(buf, sizeof buf, "threshold island: the value under the point (%g %s) is outside %g … %g%s", here,
                  intensity.unitName(), low, high,
                  (here >= low && here <= high) ? " or the voxel belongs to another structure" : "");
    return fail(buf);
  }
  Mask island = connectedRegion(inRange, *start);
  std::string how = "threshold island";
  if (options.minDiameterMm > 0) {
    // Opening by a ball of that diameter, kept to the island: bridges thinner than it are cut, and
    // only the part that holds the point (or is nearest to it) stays.
    const double r = 0.5 * options.minDiameterMm;
    const Mask core = erode(island, r);
    std::size_t seed = *start;
    if (!core.voxels[seed]) {
      const FloatVolume toPoint = [&] {
        Mask point(labels_.geometry, 0);
        point.voxels[*start] = 1;
        return distanceToMask(point);
      }();
      double best = INFINITY;
      for (std::size_t i = 0; i < core.voxels.size(); ++i)
        if (core.voxels[i] && toPoint.voxels[i] < best) best = toPoint.voxels[i], seed = i;
      if (!(best < INFINITY))
        return fail("threshold island: the region under the point is nowhere " + mm(options.minDiameterMm) +
                    " wide (lower the minimum diameter)");
    }
    const Mask kept = dilate(connectedRegion(core, seed), r);
    for (std::size_t i = 0; i < island.voxels.size(); ++i) island.voxels[i] = island.voxels[i] && kept.voxels[i];
    how += " (min diameter " + mm(options.minDiameterMm) + ")";
  }
  return commitMask(how + " '" + find(label)->displayName + "'", island, label);
}

Result<EditSummary> LabelEditor::growFromSeeds(const Volume& volume, const std::vector<GrowthSeed>& seeds,
                                               const GrowthParams& params, GrowthStats* statsOut,
                                               const LabelRanges& ranges) {
  auto stats = computeGrowth(volume, seeds, params, {}, ranges);
  if (!stats) return tl::unexpected(stats.error());
  if (statsOut) *statsOut = *stats;
  return commitGrowth(seeds.size());
}

Result<GrowthStats> LabelEditor::computeGrowth(const Volume& volume, const std::vector<GrowthSeed>& seeds,
                                               const GrowthParams& params, const WdtControl& control,
                                               const LabelRanges& ranges) {
  if (!volume.geometry.sameGridAs(labels_.geometry)) return fail("grow from seeds: the volume is not on the label map's grid");
  if (!growth_) growth_ = std::make_unique<Growth>();
  Growth& g = *growth_;
  if (!g.growth || g.volume != &volume || !(g.dims == volume.dims()) || !(g.params == params)) {
    auto made = LabelGrowth::create(volume, params);
    if (!made) return tl::unexpected(made.error());
    g.growth.emplace(std::move(*made));
    g.volume = &volume;
    g.dims = volume.dims();
    g.params = params;
  }
  g.rangedLabels.reset();
  auto stats = g.growth->update(seeds, control);
  if (!stats || stats->cancelled || ranges.empty()) return stats;
  auto ranged = g.ranged.apply(volume, g.growth->labels(), seeds, params, ranges, control, &*stats, &*g.growth);
  if (!ranged) return tl::unexpected(ranged.error());
  if (!stats->cancelled) g.rangedLabels = std::move(*ranged);
  return stats;
}

Result<EditSummary> LabelEditor::commitGrowth(std::size_t seedCount) {
  if (!growth_ || !growth_->growth) return fail("grow from seeds: nothing has been grown");
  const LabelMap& grown = growth_->rangedLabels ? *growth_->rangedLabels : growth_->growth->labels();
  Changes changes;
  for (std::size_t i = 0; i < grown.voxels.size(); ++i)
    if (grown.voxels[i] != labels_.voxels[i]) changes.push_back({i, grown.voxels[i]});
  return commit("grow from seeds (" + std::to_string(seedCount) + " seed voxels)", changes);
}

Result<EditSummary> LabelEditor::margin(std::uint16_t label, double marginMm) {
  if (auto ok = requireStructure(label); !ok) return tl::unexpected(ok.error());
  const Mask mask = maskOf(labels_, label);
  const std::string name = find(label)->displayName;
  if (marginMm >= 0) return commitMask("grow '" + name + "' by " + mm(marginMm), dilate(mask, marginMm), label, 0);
  const Mask kept = erode(mask, -marginMm);
  Mask removed(mask.geometry, 0);
  for (std::size_t i = 0; i < mask.voxels.size(); ++i) removed.voxels[i] = mask.voxels[i] && !kept.voxels[i];
  return commitMask("shrink '" + name + "' by " + mm(-marginMm), removed, 0, label);
}

Result<EditSummary> LabelEditor::hollow(std::uint16_t label, double thicknessMm) {
  if (auto ok = requireStructure(label); !ok) return tl::unexpected(ok.error());
  if (!(thicknessMm > 0)) return fail("hollow: the shell thickness must be > 0 mm");
  // The boundary voxels lie one spacing from the outside: a shell thinner than the grid's largest
  // spacing would take them too and leave nothing, so the shell is at least one voxel thick.
  const Vec3& sp = labels_.geometry.spacingMm;
  // (Distances are floats: a relative 1e-6 keeps float(spacing) > spacing from counting.)
  const Mask inside = erode(maskOf(labels_, label), std::max({thicknessMm, sp[0], sp[1], sp[2]}) * (1 + 1e-6));
  return commitMask("hollow '" + find(label)->displayName + "' to " + mm(thicknessMm), inside, 0, label);
}

Result<EditSummary> LabelEditor::smooth(std::uint16_t label, Smoothing operation, double radiusMm) {
  if (auto ok = requireStructure(label); !ok) return tl::unexpected(ok.error());
  if (!(radiusMm > 0)) return fail("smoothing: the radius must be > 0 mm");
  const Mask mask = maskOf(labels_, label);
  const std::string name = find(label)->displayName;
  if (operation == Smoothing::Opening) {
    const Mask opened = open(mask, radiusMm);
    Mask removed(mask.geometry, 0);
    for (std::size_t i = 0; i < mask.voxels.size(); ++i) removed.voxels[i] = mask.voxels[i] && !opened.voxels[i];
    return commitMask("opening of '" + name + "' (" + mm(radiusMm) + ")", removed, 0, label);
  }
  return commitMask("closing of '" + name + "' (" + mm(radiusMm) + ")", close(mask, radiusMm), label, 0);
}

void LabelEditor::beginStroke() {
  if (stroke_) endStroke();
  stroke_ = Stroke{};  // not emplace(): clang 14 (the fuzz build) takes a nested struct with member initialisers as not default-constructible here
}

std::optional<EditSummary> LabelEditor::endStroke() {
  if (!stroke_) return std::nullopt;
  const Stroke stroke = std::move(*stroke_);
  stroke_.reset();
  if (stroke.edits == 0) return std::nullopt;
  const std::string description =
      stroke.tool + (stroke.edits > 1 ? ", a stroke of " + std::to_string(stroke.edits) + " dabs" : std::string());
  EditSummary summary;
  summary.changed = history_.joinNewest(stroke.edits, [&](std::size_t voxels) {
    summary.description = description + ": " + count(voxels);
    return summary.description;
  });
  summary.historyBytes = history_.bytes();
  if (summary.changed == 0) return std::nullopt;
  return summary;
}

Result<std::string> LabelEditor::undo() {
  endStroke();  // a stroke's dabs are undone together
  return history_.undo(labels_, structures_);
}

Result<std::string> LabelEditor::redo() {
  endStroke();
  return history_.redo(labels_, structures_);
}

}  // namespace at::segment
