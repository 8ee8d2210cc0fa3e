// The segment editor's tools on the current structure (threshold island, brush, margin, hollow)
// and the structures' review states: SegmentController's commands beside its slice and growth
// (segment_controller.cpp).
#include <algorithm>

#include "segment_editor/segment_controller.h"

namespace at::app {

db::ReviewState SegmentController::reviewState(std::uint16_t label) const {
  for (const Structure& s : structures())
    if (s.label == label) {
      const auto it = review_.find(s.id);
      return it == review_.end() ? db::ReviewState::NotStarted : it->second;
    }
  return db::ReviewState::NotStarted;
}

Status SegmentController::setReviewState(std::uint16_t label, db::ReviewState state) {
  if (auto ok = requireDataset(); !ok) return ok;
  const auto s = std::find_if(structures().begin(), structures().end(), [&](const Structure& x) { return x.label == label; });
  if (s == structures().end())
    return fail(ErrorKind::NotFound, "segment editor: a review state is for a structure, and there is no label " +
                                         std::to_string(label));
  review_[s->id] = state;
  status_ = s->displayName + ": " + db::reviewStateText(state) + " (saved with the labels)";
  events_({{"event", "segment_review"}, {"structure", s->id}, {"state", db::reviewStateId(state)}});
  return {};
}

Status SegmentController::requireStructureCurrent(const std::string& tool) const {
  if (auto ok = requireDataset(); !ok) return ok;
  if (current_ == 0) return fail("segment editor: " + tool + " works on a structure; choose one (not the background) first");
  return {};
}

std::array<double, 2> SegmentController::valueWindow() const {
  if (!dataset_) return {0, 1};
  const IntensityModel& m = dataset_->intensity;
  return {m.valueOf(m.window[0]), m.valueOf(m.window[1])};
}

Result<segment::EditSummary> SegmentController::thresholdIsland(const std::array<int, 3>& voxel, double low, double high,
                                                                 double minDiameterMm) {
  if (auto ok = requireStructureCurrent("threshold island"); !ok) return tl::unexpected(ok.error());
  const Geometry& g = dataset_->volume.geometry;
  if (!g.dims.contains(voxel[0], voxel[1], voxel[2]))
    return fail("segment editor: voxel (" + std::to_string(voxel[0]) + ", " + std::to_string(voxel[1]) + ", " +
                std::to_string(voxel[2]) + ") is outside the volume (" + g.dims.toString() + ")");
  segment::ThresholdOptions options;
  options.minDiameterMm = std::max(0.0, minDiameterMm);
  const Vec3 point = g.indexToPatient({double(voxel[0]), double(voxel[1]), double(voxel[2])});
  auto summary = editor_->thresholdIsland(*grown_, dataset_->intensity, point, low, high, current_, options);
  if (!summary) return summary;
  edited("segment_edited", "threshold", *summary);
  return summary;
}

Result<segment::EditSummary> SegmentController::brushAt(const Vec3& pointMm) {
  if (auto ok = requireDataset(); !ok) return tl::unexpected(ok.error());
  if (tool != Tool::Paint && tool != Tool::Erase)
    return fail("segment editor: the brush paints or erases labels; choose the paint or erase tool first");
  if (tool == Tool::Paint)
    if (auto ok = requireStructureCurrent("paint"); !ok) return tl::unexpected(ok.error());
  const double radius = std::max(0.0, brushMm);
  auto summary = tool == Tool::Paint ? editor_->paint(pointMm, radius, current_) : editor_->erase(pointMm, radius);
  if (!summary) return summary;
  edited("segment_edited", tool == Tool::Paint ? "paint" : "erase", *summary,
         {{"point_mm", {pointMm[0], pointMm[1], pointMm[2]}}, {"radius_mm", radius}}, false);
  return summary;
}

Result<segment::EditSummary> SegmentController::brushAtVoxel(const std::array<int, 3>& voxel) {
  if (auto ok = requireDataset(); !ok) return tl::unexpected(ok.error());
  return brushAt(dataset_->volume.geometry.indexToPatient({double(voxel[0]), double(voxel[1]), double(voxel[2])}));
}

void SegmentController::beginStroke() {
  if (editor_) editor_->beginStroke();
}

void SegmentController::endStroke() {
  if (!editor_) return;
  if (auto stroke = editor_->endStroke()) status_ = stroke->description;
}

Result<segment::EditSummary> SegmentController::margin(double mm) {
  if (auto ok = requireStructureCurrent("margin"); !ok) return tl::unexpected(ok.error());
  auto summary = editor_->margin(current_, mm);
  if (!summary) return summary;
  edited("segment_edited", "margin", *summary);
  return summary;
}

Result<segment::EditSummary> SegmentController::hollow(double thicknessMm) {
  if (auto ok = requireStructureCurrent("hollow"); !ok) return tl::unexpected(ok.error());
  auto summary = editor_->hollow(current_, thicknessMm);
  if (!summary) return summary;
  edited("segment_edited", "hollow", *summary);
  return summary;
}

Result<segment::IslandSplit> SegmentController::splitIslands(double minDiameterMm, std::size_t minVoxels) {
  if (auto ok = requireStructureCurrent("split islands"); !ok) return tl::unexpected(ok.error());
  auto split = editor_->splitIslands(current_, minDiameterMm, minVoxels);
  if (!split) return split;
  edited("segment_edited", "split_islands", split->summary, {{"new_labels", split->newLabels}}, true);
  return split;
}

}  // namespace at::app
