// DesktopModel: what lessons, the course editor's preview and its capture put on the view
// (declared in desktop_model.h under "Commands"; the lesson and course-editor callbacks).
#include "core/strings.h"
#include "course_views.h"
#include "desktop_model.h"
#include "lesson_player/lesson_field_needs.h"

namespace at::app {

void DesktopModel::showLessonStructure(const LessonController::Shown& shown) {
  auto preset = presetForStep(library_, shown.structure, shown.presetId, explore_.levels(), &session_.database());
  if (!preset) {
    message(preset.error().message);
    return;
  }
  showStructureWith(shown, *preset);
  closeAnswerSlice();  // the step before's "show me on a slice" ends here
  if (shown.onSlice)
    if (auto st = showAnswerSlice(shown.structure); !st) message("show me on a slice: " + st.error().message);
}

void DesktopModel::showStructureWith(const LessonController::Shown& shown, const render::Preset& preset) {
  const Structure* s = dataset_->findStructure(shown.structure);
  if (!s || !explore_.hasStructure(s->label)) {
    message("lesson step: no structure '" + shown.structure + "' in dataset '" + dataset_->id + "'");
    return;
  }
  explore_.usePreset(s->label, preset, preset.t);
  setHovered(0);
  select(s->label, Framing::kKeepCamera);  // the step's view frames it below
  const std::string view =
      shown.view ? lessons::toString(*shown.view) : (explore_.viewName().empty() ? startView_ : explore_.viewName());
  const Structure* alsoInView = shown.alsoInView.empty() ? nullptr : dataset_->findStructure(shown.alsoInView);
  if (auto st = explore_.setView(view, layout_.viewPixelsW(), layout_.viewPixelsH(), alsoInView ? alsoInView->label : 0); !st)
    message(st.error().message);
  if (shown.camera) explore_.setCamera(cameraOf(*shown.camera));
  // The step's plane, else none: the student sees what the author captured.
  ClipSettings clip;
  if (shown.clip) {
    const render::ClipPlane plane = clipOf(*shown.clip);
    for (int axis = 0; axis < 3; ++axis)
      if (plane.normal[std::size_t(axis)] != 0) clip.axis = axis;
    clip.on = true;
    clip.flip = plane.normal[std::size_t(clip.axis)] < 0;
    clip.offsetMm = float(plane.d - dot(plane.normal, explore_.camera().target));
  }
  explore_.setClip(clip);
}

void DesktopModel::prefetchLessonFields() {
  const auto& step = lessons_->step();
  const lessons::LessonEngine* engine = lessons_->engine();
  std::string key;
  if (step && engine && !lessons_->finishedScore() && options_.prefetchLessonFields)
    key = engine->lesson().id + "#" + std::to_string(step->index);
  if (key == prefetchedFor_) return;
  prefetchedFor_ = key;
  std::vector<wdt::FieldRequest> requests;
  if (!key.empty()) {
    const auto& steps = engine->lesson().steps;
    // Every step the lesson will still show; FieldView::prefetch keeps what fits its budget.
    const std::vector<int> upcoming = engine->upcomingSteps(int(steps.size()));
    for (const LessonFieldNeed& need : lessonFieldNeeds(steps, step->index, upcoming)) {
      const Structure* s = dataset_->findStructure(need.structure);
      if (!s) continue;
      if (need.kind == LessonFieldNeed::Kind::AnswerKey) {
        requests.push_back(FieldView::answerKeyRequest(s->label));
        continue;
      }
      auto preset = presetForStep(library_, need.structure, need.presetId, explore_.levels(), &session_.database());
      if (!preset || preset->mode == render::RenderMode::Bare) continue;
      if (auto params = render::wdtParamsFor(*preset)) requests.push_back(FieldView::viewFieldRequest(s->label, *params));
    }
  }
  const std::size_t kept = fields_->prefetch(requests);
  if (kept > 0) event({{"event", "prefetch"}, {"step", step->index}, {"fields", kept}});
}

bool DesktopModel::previewHidesNames() const {
  const auto& preview = courses_->previewing();
  // Selecting another structure (or closing the editor) ends what the student would see.
  return courses_->windowOpen && preview && preview->namesHidden && idOf(explore_.selected()) == preview->structure;
}

std::string DesktopModel::courseDatasetId() const {
  return str::startsWith(dataset_->id, "phantom:") ? std::string("phantom") : dataset_->id;
}

Result<CourseEditor::Capture> DesktopModel::captureView() const {
  const std::uint16_t label = explore_.selected();
  if (!label) return fail("select the structure to show first");
  CourseEditor::Capture capture;
  capture.structure = idOf(label);
  capture.preset = explore_.presetOverridden() ? explore_.shown().preset : explore_.presetOf(label, explore_.bare());
  capture.preset.t = explore_.t();
  auto view = lessons::parseCameraView(explore_.viewName().empty() ? startView_ : explore_.viewName());
  if (!view) return tl::unexpected(view.error());
  capture.view = *view;
  capture.camera = stepCameraOf(explore_.camera());
  if (auto plane = explore_.clipPlane()) {
    auto clip = stepClipOf(*plane);
    if (!clip) return tl::unexpected(clip.error());
    capture.clip = *clip;
  }
  return capture;
}

lessons::RenderState DesktopModel::renderState() const {
  const render::Preset p = explore_.shown().preset;
  lessons::RenderState r;
  r.presetId = p.id.value_or(p.name);
  r.mode = explore_.bare() ? "bare" : "wdt";
  r.t = explore_.t();
  r.alpha = p.alpha;
  r.beta = p.lightingBeta;
  return r;
}

}  // namespace at::app
