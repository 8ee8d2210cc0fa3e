// DesktopModel: the pointer on the 3-D view — hover and pick (what is under the cursor), clicks
// (select, paint, answer a locate question) and where a structure lies on screen (desktop_model.h).
#include <array>
#include <optional>

#include "desktop_model.h"
#include "render/structure_pick.h"
#include "segment_editor/segment_controller.h"

namespace at::app {

using json = nlohmann::json;

void DesktopModel::setHovered(std::uint16_t label) {
  if (!explore_.setHovered(label)) {
    explore_.noteActivity();
    return;
  }
  fields_->hoverChanged();
  const std::uint16_t shown = explore_.shownLabel();
  if (explore_.bare() || shown != explore_.fieldLabel()) recorder_.highlightWanted(shown, Clock::now());
  else recorder_.highlightNotWanted();
}

render::PickResult DesktopModel::pickAt(double x, double y, std::optional<double> surfaceOpacity) const {
  render::RenderSettings s = renderSettings(scheduler_.planFor(kFullLevel));
  s.preset = explore_.pickPreset();
  render::SceneVolumes scene;
  scene.volume = &dataset_->volume;
  scene.labels = &dataset_->labels;
  const DistanceField* field = fields_->pickField();
  scene.field = field ? &field->distances : nullptr;
  scene.gradients = &gradients_;
  scene.selected = explore_.fieldLabel();
  const render::TransferFunction2D& table = pickTables_.tableFor(s.preset);
  const double px = (x - layout_.viewLeft()) / layout_.viewWidth() * s.width;
  const double py = y / layout_.viewHeight() * s.height;
  if (surfaceOpacity) return render::pick(scene, s, table, px, py, *surfaceOpacity);
  return render::pickStructure(scene, s, table, px, py);
}

void DesktopModel::hoverAt(double x, double y) {
  if (study_->participantActive()) return;  // the view stays on the trial's structure
  if (!layout_.inView(x, y)) {
    setHovered(0);
    return;
  }
  const render::PickResult hit = pickAt(x, y);
  if (hit.hit) lastPickMm_ = hit.pointMm;
  else lastPickMm_.reset();
  const std::uint16_t label = hit.hit && explore_.hasStructure(hit.label) ? hit.label : 0;
  if (label != explore_.hovered()) {
    json e = {{"event", "hover"}, {"x", x}, {"y", y}, {"label", label}, {"structure", idOf(label)}};
    if (label) {  // the colour its WDT preset draws the structure itself in (render_settings.h)
      const auto& rgb = explore_.presetOf(label, false).highlightRgb;
      e["highlight_rgb"] = {rgb[0], rgb[1], rgb[2]};
    }
    event(e);
  }
  setHovered(label);
}

void DesktopModel::clickAt(double x, double y) {
  if (study_->participantActive()) return;
  if (segment_->brushesInView()) {  // the click paints (or erases) instead of selecting
    segment_->beginStroke();
    brushAt(x, y);
    segment_->endStroke();
    return;
  }
  hoverAt(x, y);
  if (lastPickMm_ && !namesHidden() && slices_.moveToPoint(*lastPickMm_)) {
    const auto& v = slices_.crosshair();
    event({{"event", "crosshair"}, {"voxel", {v[0], v[1], v[2]}}});
  }
  if (exams_->wantsClick() || lessons_->wantsClick()) {
    answerLocate(dataset_->findStructureByLabel(explore_.hovered()), lastPickMm_);
    return;
  }
  if (exams_->running()) return;  // the item's view stays
  if (explore_.hovered()) select(explore_.hovered(), Framing::kKeepCamera);
}

void DesktopModel::answerLocate(const Structure* clicked, const std::optional<Vec3>& pointMm) {
  // For a question with a tolerance that was missed, the clicked point's weighted distance from
  // the target (else unknown: -1).
  const bool exam = exams_->wantsClick() || exams_->wantsSliceClick();
  const auto targetId = exam ? exams_->itemTarget() : lessons_->questionTarget();
  const Structure* target = targetId ? dataset_->findStructure(*targetId) : nullptr;
  const bool distance = exam ? exams_->acceptsClickDistance() : lessons_->wantsClickDistance();
  const std::string id = clicked ? clicked->id : "";
  if (distance && target && clicked != target && pointMm)
    fields_->gradeClickDistance(id, target->label, *pointMm);
  else
    clickGraded(id, -1);
}

void DesktopModel::clickGraded(const std::string& clicked, double distanceMm) {
  if (!exams_->clicked(clicked, distanceMm)) lessons_->clicked(clicked, distanceMm);
}

std::optional<std::array<double, 2>> DesktopModel::projectStructure(std::uint16_t label) const {
  const render::StructureFrame* frame = explore_.frameOf(label);
  if (!frame) return std::nullopt;
  const double left = layout_.viewLeft();
  const int viewW = int(layout_.viewWidth()), viewH = int(layout_.viewHeight());
  auto p = explore_.camera().project(frame->anchorMm, viewW, viewH);
  if (!p || (*p)[0] < 0 || (*p)[0] >= viewW || (*p)[1] < 0 || (*p)[1] >= viewH) return std::nullopt;
  return std::array<double, 2>{(*p)[0] + left, (*p)[1]};
}

}  // namespace at::app
