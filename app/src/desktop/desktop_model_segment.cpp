// DesktopModel: the segment editor's brush on the 3-D view (desktop_model.h, brushAt) and its
// labels shown there as they are edited (showEditedLabels).
#include <algorithm>
#include <climits>
#include <cstring>

#include "desktop_model.h"
#include "segment_editor/segment_controller.h"

namespace at::app {

namespace {
// The brush's centre: where the ray's accumulated opacity reaches a quarter — the first surface
// the user sees (a translucent CT shows its skin as a shell of about that), not the sample behind
// it where a hover's pick (kSeenThroughOpacity) looks through bone.
constexpr double kBrushSurfaceOpacity = 0.25;

bool sameStructure(const Structure& a, const Structure& b) {
  return a.label == b.label && a.id == b.id && a.displayName == b.displayName && a.colour == b.colour &&
         a.system == b.system && a.description == b.description;
}

// Where `after` differs from `before` (an empty map: all background): the box of the voxels that
// differ and every label they had or have (in `labels`, marked by value).
struct LabelDiff {
  std::array<int, 6> box{INT_MAX, INT_MAX, INT_MAX, -1, -1, -1};
  bool any() const { return box[3] >= 0; }
};
LabelDiff diffLabels(const LabelMap& before, const LabelMap& after, std::vector<bool>& labels) {
  LabelDiff diff;
  const Dims& d = after.dims();
  const std::vector<std::uint16_t> zeros(std::size_t(d.x), 0);
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j) {
      const std::size_t row = d.index(0, j, k);
      const std::uint16_t* a = before.empty() ? zeros.data() : before.voxels.data() + row;
      const std::uint16_t* b = after.voxels.data() + row;
      if (std::memcmp(a, b, std::size_t(d.x) * sizeof(std::uint16_t)) == 0) continue;  // most rows
      for (int i = 0; i < d.x; ++i) {
        if (a[i] == b[i]) continue;
        labels[a[i]] = labels[b[i]] = true;
        const int at[3] = {i, j, k};
        for (std::size_t axis = 0; axis < 3; ++axis) {
          diff.box[axis] = std::min(diff.box[axis], at[axis]);
          diff.box[axis + 3] = std::max(diff.box[axis + 3], at[axis] + 1);
        }
      }
    }
  return diff;
}
}  // namespace

void DesktopModel::showEditedLabels() {
  if (!segment_->attached() || segment_->labelsRevision() == editorLabelsRevision_) return;
  editorLabelsRevision_ = segment_->labelsRevision();
  const Clock::time_point start = Clock::now();
  const LabelMap& edited = segment_->labels();
  std::vector<bool> marked(65536, false);
  const LabelDiff diff = diffLabels(dataset_->labels, edited, marked);
  // Structures added, removed or changed (a rename or a colour) count as edited labels too.
  const std::vector<Structure>& before = dataset_->structures;
  const std::vector<Structure>& after = segment_->structures();
  for (const auto* list : {&before, &after})
    for (const Structure& s : *list) {
      const auto& other = list == &before ? after : before;
      const auto same = std::find_if(other.begin(), other.end(), [&](const Structure& o) { return sameStructure(s, o); });
      if (same == other.end()) marked[s.label] = true;
    }
  std::vector<std::uint16_t> changed;
  for (std::size_t v = 1; v < marked.size(); ++v)
    if (marked[v]) changed.push_back(std::uint16_t(v));
  if (changed.empty()) return;
  fields_->labelsChanged(
      [&] {
        LabelMap& shown = dataset_->labels;
        if (shown.empty()) shown = LabelMap(dataset_->volume.geometry, 0);
        if (!diff.any()) return;
        const Dims& d = shown.dims();
        const std::size_t width = std::size_t(diff.box[3] - diff.box[0]);
        for (int k = diff.box[2]; k < diff.box[5]; ++k)
          for (int j = diff.box[1]; j < diff.box[4]; ++j) {
            const std::size_t row = d.index(diff.box[0], j, k);
            std::copy_n(edited.voxels.begin() + std::ptrdiff_t(row), width, shown.voxels.begin() + std::ptrdiff_t(row));
          }
      },
      changed);
  dataset_->structures = after;
  const std::uint16_t selectedBefore = explore_.selected();
  explore_.labelsEdited(changed, segment_->currentLabel(), diff.any() ? std::optional(diff.box) : std::nullopt);
  // An edited structure's full-resolution field waits until the edits pause (as a hover rests).
  if (std::find(changed.begin(), changed.end(), explore_.shownLabel()) != changed.end()) fields_->hoverChanged();
  if (diff.any()) labelEdit_ = {labelEdit_.revision + 1, diff.box};
  nlohmann::json e = {{"event", "labels_shown"}, {"changed", changed}, {"whole_volume", explore_.wholeVolume()},
            {"selected", idOf(explore_.selected())}, {"ms", msBetween(start, Clock::now())}};
  if (diff.any()) e["box"] = diff.box;
  event(e);
  if (explore_.selected() != selectedBefore && explore_.selected())
    event({{"event", "select"}, {"label", explore_.selected()}, {"structure", idOf(explore_.selected())}});
}

void DesktopModel::brushAt(double x, double y) {
  if (!layout_.inView(x, y) || study_->participantActive()) return;
  const render::PickResult surface = pickAt(x, y, kBrushSurfaceOpacity);
  if (!surface.hit) return;  // off the volume: nothing
  auto dab = segment_->brushAt(surface.pointMm);
  if (!dab) {
    message(dab.error().message);
    return;
  }
  // The slices follow the brush, so the painted ball shows in them (as a 3-D pick moves them).
  if (slices_.moveToPoint(surface.pointMm)) {
    const auto& v = slices_.crosshair();
    event({{"event", "crosshair"}, {"voxel", {v[0], v[1], v[2]}}});
    (void)segment_->setSlice(segment_->axis(), v[std::size_t(segment_->axis())]);
  }
}

}  // namespace at::app
