// DesktopModel: what the view shows for an exam item (desktop_model.h, "Exams").
#include <cmath>
#include <limits>

#include "desktop_model.h"
#include "render/target_side.h"
#include "slice_marking.h"

namespace at::app {

using json = nlohmann::json;

void DesktopModel::showExamItem(const std::optional<ExamController::ItemScene>& item) {
  turnToward_.reset();
  examSlice_.reset();
  if (!item) return;
  showLessonStructure({item->scene.structure, item->scene.presetId, item->scene.view, std::nullopt, std::nullopt, {}, false});
  if (item->answerOnSlice) {
    if (auto st = showAnswerSlice(item->target); !st) message("exam review: " + st.error().message);
    return;
  }
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
  auto slice = anchorSlice(*target, false);  // no labels: the student finds the target
  if (!slice) {
    message("exam slice: " + slice.error().message);
    return;
  }
  examSlice_ = std::move(*slice);
  event({{"event", "exam_slice"}, {"axis", examSlice_->request.axis}, {"index", examSlice_->request.index},
         {"edges", examSlice_->request.layout->edgeLetters()},
         {"width", examSlice_->image.width}, {"height", examSlice_->image.height}});
}

Result<DesktopModel::ExamSlice> DesktopModel::anchorSlice(const Structure& target, bool highlight) {
  const render::StructureFrame* frame = explore_.frameOf(target.label);
  if (!frame) return fail("structure '" + target.id + "' has no voxels in dataset '" + dataset_->id + "'");
  ExamSlice slice;
  slice.request = anchorSliceRequest(dataset_->labels.geometry, frame->anchorMm);  // patient orientation
  const std::vector<Structure> only{target};
  if (highlight) slice.request.labelAlpha = 0.65;
  auto image = renderSlice(dataset_->volume, highlight ? &dataset_->labels : nullptr, highlight ? only : dataset_->structures,
                           slice.request);
  if (!image) return tl::unexpected(image.error());
  if (highlight) frameStructureOnSlice(*image, dataset_->labels, slice.request, target.label);
  slice.image = std::move(*image);
  slice.revision = ++sliceRevision_;
  if (highlight) slice.highlighted = target.id;
  return slice;
}

Status DesktopModel::showAnswerSlice(const std::string& structureId) {
  const Structure* target = dataset_->findStructure(structureId);
  if (!target) return fail("no structure '" + structureId + "' in dataset '" + dataset_->id + "'");
  auto slice = anchorSlice(*target, true);
  if (!slice) return tl::unexpected(slice.error());
  examSlice_ = std::move(*slice);
  event({{"event", "answer_slice"}, {"structure", structureId}, {"axis", examSlice_->request.axis},
         {"index", examSlice_->request.index}, {"edges", examSlice_->request.layout->edgeLetters()},
         {"width", examSlice_->image.width}, {"height", examSlice_->image.height}});
  return {};
}

void DesktopModel::closeAnswerSlice() {
  if (examSlice_ && !examSlice_->highlighted.empty()) examSlice_.reset();
}

void DesktopModel::turnTowardTarget() {
  if (!turnToward_ || !fields_->settled() || (!explore_.bare() && !fields_->pickField())) return;
  const Turn turn = *std::exchange(turnToward_, std::nullopt);
  // The sides as `play` and `exam` try them (render/target_side.h), each set and picked here.
  const double left = layout_.viewLeft();
  const int viewW = int(layout_.viewWidth()), viewH = int(layout_.viewHeight());
  const auto side = render::firstSideShowingTarget(turn.view, [&](const std::string& view) -> Result<bool> {
    if (!setView(view)) return false;
    return render::targetClickableAt(explore_.camera(), viewW, viewH, dataset_->labels, turn.target, explore_.clipPlane(),
                                     [&](double x, double y) { return pickAt(x + left, y); });
  });
  const std::optional<std::string> chosen = side ? *side : std::nullopt;  // the search itself cannot fail here
  if (!chosen)
    if (auto st = setView(turn.view); !st) message(st.error().message);
  event({{"event", "exam_view"}, {"view", chosen.value_or(turn.view)}, {"target_visible", chosen.has_value()}});
}

void DesktopModel::clickSlice(double x, double y) {
  if (!examSlice_ || !examSlice_->highlighted.empty() || !exams_->wantsSliceClick()) return;
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
