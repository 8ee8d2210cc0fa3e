// DesktopModel: what the view shows for an exam item (desktop_model.h, "Exams").
#include <cmath>
#include <limits>

#include "desktop_model.h"
#include "render/target_side.h"

namespace at::app {

using json = nlohmann::json;

void DesktopModel::showExamItem(const std::optional<ExamController::ItemScene>& item) {
  turnToward_.reset();
  examSlice_.reset();
  if (!item) return;
  showLessonStructure({item->scene.structure, item->scene.presetId, item->scene.view, std::nullopt, std::nullopt, {}});
  if (!item->locate) return;
  const Structure* target = dataset_->findStructure(item->target);
  if (!target) {
    message("exam item: no structure '" + item->target + "' in dataset '" + dataset_->id + "'");
    return;
  }
  if (!item->slice) {
    turnToward_ = Turn{target->label, lessons::toString(item->scene.view)};
    return;
  }
  // The axial slice through the target's anchor (its voxel nearest its centroid).
  const render::StructureFrame* frame = explore_.frameOf(target->label);
  if (!frame) {
    message("exam item: structure '" + item->target + "' has no voxels in dataset '" + dataset_->id + "'");
    return;
  }
  ExamSlice slice;
  slice.request.axis = 2;
  slice.request.index = int(std::lround(dataset_->labels.geometry.patientToIndex(frame->anchorMm)[2]));
  auto image = renderSlice(dataset_->volume, nullptr, dataset_->structures, slice.request);  // no labels
  if (!image) {
    message("exam slice: " + image.error().message);
    return;
  }
  slice.image = std::move(*image);
  slice.revision = ++sliceRevision_;
  examSlice_ = std::move(slice);
  event({{"event", "exam_slice"}, {"axis", 2}, {"index", examSlice_->request.index},
         {"width", examSlice_->image.width}, {"height", examSlice_->image.height}});
}

void DesktopModel::turnTowardTarget() {
  if (!turnToward_ || !fields_->settled() || (!explore_.bare() && !fields_->pickField())) return;
  const Turn turn = *std::exchange(turnToward_, std::nullopt);
  // The sides as `play` and `exam` try them (render/target_side.h), each set and picked here.
  const double left = layout_.viewLeft();
  const int viewW = int(layout_.viewWidth()), viewH = int(layout_.viewHeight());
  const auto side = render::firstSideShowingTarget(turn.view, [&](const std::string& view) -> Result<bool> {
    const render::StructureFrame* frame = explore_.frameOf(turn.target);
    if (!frame || !setView(view)) return false;
    return render::targetClickableAt(explore_.camera(), viewW, viewH, frame->anchorMm, turn.target,
                                     [&](double x, double y) { return pickAt(x + left, y); });
  });
  const std::optional<std::string> chosen = side ? *side : std::nullopt;  // the search itself cannot fail here
  if (!chosen)
    if (auto st = setView(turn.view); !st) message(st.error().message);
  event({{"event", "exam_view"}, {"view", chosen.value_or(turn.view)}, {"target_visible", chosen.has_value()}});
}

void DesktopModel::clickSlice(double x, double y) {
  if (!examSlice_ || !exams_->wantsSliceClick()) return;
  const auto ijk = sliceVoxelAt(dataset_->labels.dims(), examSlice_->request, x, y);
  if (!ijk) return;  // outside the slice: no answer
  const std::uint16_t label = dataset_->labels.at((*ijk)[0], (*ijk)[1], (*ijk)[2]);
  const Vec3 point = dataset_->labels.geometry.indexToPatient({double((*ijk)[0]), double((*ijk)[1]), double((*ijk)[2])});
  event({{"event", "slice_click"}, {"x", x}, {"y", y}, {"voxel", *ijk}});
  answerLocate(dataset_->findStructureByLabel(label), point);
}

std::optional<std::array<double, 2>> DesktopModel::slicePixelOf(std::uint16_t label) const {
  if (!examSlice_) return std::nullopt;
  const int w = examSlice_->image.width, h = examSlice_->image.height;
  const SliceRequest& r = examSlice_->request;
  std::vector<std::array<double, 2>> pixels;
  double sx = 0, sy = 0;
  for (int y = 0; y < h; y += r.scale)
    for (int x = 0; x < w; x += r.scale) {
      const auto ijk = sliceVoxelAt(dataset_->labels.dims(), r, x, y);
      if (!ijk || dataset_->labels.at((*ijk)[0], (*ijk)[1], (*ijk)[2]) != label) continue;
      pixels.push_back({x + 0.5 * r.scale, y + 0.5 * r.scale});
      sx += pixels.back()[0];
      sy += pixels.back()[1];
    }
  if (pixels.empty()) return std::nullopt;
  const double cx = sx / double(pixels.size()), cy = sy / double(pixels.size());
  std::array<double, 2> best = pixels.front();
  double bestD = std::numeric_limits<double>::max();
  for (const auto& p : pixels)
    if (const double d = std::hypot(p[0] - cx, p[1] - cy); d < bestD) {
      bestD = d;
      best = p;
    }
  return best;
}

}  // namespace at::app
