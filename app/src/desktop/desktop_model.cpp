// [SECTIONS] opening datasets · commands · frames
#include "desktop_model.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/strings.h"
#include "course_views.h"
#include "dataset_resolver.h"
#include "intensity_notes.h"
#include "db/dataset_store.h"
#include "volume/known_scans.h"
#include "render/derived_preset.h"
#include "render/field_scale.h"
#include "render/volume_preset.h"
#include "segment_editor/segment_controller.h"

namespace at::app {

using json = nlohmann::json;

int ViewLayout::viewPixelsW() const {
  return std::max(1, int(std::lround(viewWidth() * double(framebufferW) / std::max(1, windowW))));
}

int ViewLayout::viewPixelsH() const {
  return std::max(1, int(std::lround(viewHeight() * double(framebufferH) / std::max(1, windowH))));
}

void dockPanels(ViewLayout& layout, bool editor, bool slices, bool expert) {
  layout.rightPx = layout.bottomPx = layout.expertPx = 0;
  const float s = layout.uiScale, w = float(layout.windowW);
  if (expert && w - layout.panelWidth() - kExpertPanelPx * s >= kMinDockedViewPx * s) layout.expertPx = kExpertPanelPx * s;
  if (!editor) return;
  const float column = std::clamp(0.3f * w, 340 * s, 520 * s);
  const float viewLeft = w - layout.panelWidth() - layout.expertPx - column;
  if (viewLeft < kMinDockedViewPx * s) return;  // too narrow: floating windows
  layout.rightPx = column;
  // The three panes side by side under the view, each about a third of its width square.
  if (slices) layout.bottomPx = std::min(0.36f * float(layout.windowH), viewLeft / 3 + 56 * s);
}

DesktopModel::DesktopModel(LearningSession& session, const render::PresetLibrary& library, DesktopOptions options,
                           EventSink events, MessageSink messages)
    : session_(session),
      library_(library),
      options_(std::move(options)),
      events_(std::move(events)),
      messageSink_(std::move(messages)),
      fieldUnits_(options_.measureFieldUnit, options_.scripted),
      explore_(library, [this](const std::string& m) { message(m); }),
      scheduler_(options_.frameBudgetMs, options_.renderScale) {
  const auto sink = [this](json j) { event(std::move(j)); };
  lessons_ = std::make_unique<LessonController>(
      session_, options_.userName, "", sink, [this](const LessonController::Shown& shown) { showLessonStructure(shown); },
      [this] { return renderState(); });
  exams_ = std::make_unique<ExamController>(
      session_, *lessons_, sink, [this](const std::optional<ExamController::ItemScene>& item) { showExamItem(item); },
      [this] { return renderState(); });
  analytics_ = std::make_unique<AnalyticsController>(session_, sink);
  study_ = std::make_unique<StudyController>(session_.database(), library_, sink,
                                             [this]() -> Result<render::IntensityLevels> { return explore_.levels(); });
  imports_ = std::make_unique<ImportController>(session_.database(), sink, [this](const std::string& m) { message(m); });
  segment_ = std::make_unique<SegmentController>(session_.database(), sink);
  courses_ = std::make_unique<CourseEditor>(session_, library_, sink,
                                            [this](const lessons::QuestionScene& scene, const std::optional<render::Preset>& captured) {
                                              const LessonController::Shown shown{scene.structure, scene.presetId, scene.view,
                                                                                  scene.camera, scene.clip, {}};
                                              if (captured) showStructureWith(shown, *captured);
                                              else showLessonStructure(shown);
                                            },
                                            [this](const quiz::Question& q, const lessons::QuestionScene& scene,
                                                   const render::Preset& preset) { return locateCheckWork(q, scene, preset); });
  scheduler_.setViewPixels(layout_.viewPixelsW(), layout_.viewPixelsH());
  classEvents_ = std::make_unique<BackgroundOutboxSender>(session_.database(), std::chrono::seconds(5));
}

DesktopModel::~DesktopModel() = default;

std::string DesktopModel::idOf(std::uint16_t label) const {
  const Structure* s = dataset_ ? dataset_->findStructureByLabel(label) : nullptr;
  return s ? s->id : "";
}

void DesktopModel::message(const std::string& text) {
  messages_.push_back(text);
  if (messages_.size() > 6) messages_.erase(messages_.begin());
  std::fprintf(stderr, "anatomy-tutor: %s\n", text.c_str());
  if (messageSink_) messageSink_(text);
}

void DesktopModel::note(const std::string& text) {
  notes_.push_back(text);
  if (notes_.size() > 3) notes_.erase(notes_.begin());
  report(text);
}

void DesktopModel::report(const std::string& text) {
  std::fprintf(stderr, "anatomy-tutor: %s\n", text.c_str());
  if (messageSink_) messageSink_(text);
}

// ---------------------------------------------------------------------------------------------
// Opening datasets

Status DesktopModel::open() {
  // A course by id: a file of the course folder, else any course stored in the database (imported
  // with `course import`, saved by the course editor), as `courses` lists them.
  auto course = loadStartCourse(options_.course);
  if (!course && !options_.course.empty() && course.error().kind == ErrorKind::NotFound)
    if (auto stored = session_.curriculum().course(options_.course)) course = std::move(*stored);
  if (!course && !options_.course.empty()) return tl::unexpected(course.error());
  std::string datasetName = options_.dataset;
  std::string startStructure, startPreset;
  if (course) {
    if (datasetName.empty()) datasetName = course->datasetId;
    const auto views = firstLessonViews(*course);
    if (!views.empty()) {
      startStructure = views.front().structure;
      startPreset = views.front().presetId;
      startView_ = lessons::toString(views.front().view);
    }
  } else {
    message("default course: " + course.error().message);
  }
  if (datasetName.empty()) datasetName = "phantom";
  DatasetRequest request;
  request.name = datasetName;
  request.database = &session_.database();
  auto ds = openNamedDataset(request);
  if (!ds) return tl::unexpected(ds.error());
  if (auto st = showDataset(std::move(*ds), startStructure, startPreset); !st) return st;
  // The lessons panel starts on the course the view opened for, not on the first course stored.
  if (course) lessons_->preferCourse(course->id);
  opened_ = true;
  return {};
}

Status DesktopModel::showDataset(Dataset dataset, const std::string& startStructure, const std::string& startPreset) {
  auto next = std::make_unique<Dataset>(std::move(dataset));
  // The CT table, headrest and other objects outside the body are no context: left out here as the
  // render command leaves them out (derived_preset.h), before anything reads the volume; the
  // segment editor grows on the volume as loaded, as `anatomy-tutor segment` does (scan_volumes.h).
  ShownScan shown = leaveOutNonAnatomyForShowing(*next);
  if (expert_ && expertOn()) setExpert(false);
  if (auto st = explore_.setDataset(*next, startStructure, startPreset); !st) return st;
  fields_.reset();  // it refers to the dataset being replaced
  fieldUnits_.reset();  // a running measure reads the volume being replaced
  segment_->stopGrowth();  // it reads the volumes being replaced
  courses_->stopCheck();    // so does a locate question's check
  locateChecker_.reset();
  dataset_ = std::move(next);
  gradients_ = render::computeGradientVolume(dataset_->volume);
  ++datasetRevision_;
  const auto sink = [this](json j) { event(std::move(j)); };
  fields_ = std::make_unique<FieldView>(
      *dataset_, explore_, sink, [this](const std::string& m) { message(m); },
      [this](const std::string& clicked, double distanceMm) { clickGraded(clicked, distanceMm); },
      [this](const std::string& m) { note(m); });
  expert_ = std::make_unique<TfEditor>(*dataset_, session_.database(), sink);
  shown_ = std::move(shown);
  segment_->attach(*dataset_, &shown_.growthVolume(*dataset_));
  editorLabelsRevision_ = segment_->labelsRevision();
  slices_.attach(*dataset_);
  recorder_.highlightNotWanted();
  lastPickMm_.reset();
  lessons_->setViewDataset(dataset_->id);
  // Shown with the dataset's name for as long as it is shown (the notes keep only the last few).
  datasetCaution_ = densityWeightsNote(*dataset_);
  if (datasetCaution_) report(*datasetCaution_);
  reframe();
  if (opened_)
    event({{"event", "dataset"}, {"dataset", dataset_->id}, {"structures", dataset_->structures.size()},
           {"selected", idOf(explore_.selected())}});
  return {};
}

std::vector<std::string> DesktopModel::datasetChoices() {
  std::vector<std::string> names{"phantom"};
  if (const KnownScan* skull = findKnownScan("skull"); skull && knownScanFile(*skull)) names.push_back("skull");
  if (auto imported = db::listDatasets(session_.database()))
    for (const db::DatasetRecord& r : *imported) names.push_back(r.name);
  return names;
}

Status DesktopModel::switchDataset(const std::string& name) {
  DatasetRequest request;
  request.name = name;
  request.database = &session_.database();
  auto dataset = openNamedDataset(request);
  if (!dataset) return tl::unexpected(dataset.error());
  return showDataset(std::move(*dataset), "", "");
}

// ---------------------------------------------------------------------------------------------
// Commands

void DesktopModel::setLayout(const ViewLayout& layout) {
  if (layout == layout_) return;
  const bool docking = layout.rightPx != layout_.rightPx || layout.bottomPx != layout_.bottomPx || layout.expertPx != layout_.expertPx;
  layout_ = layout;
  scheduler_.setViewPixels(layout.viewPixelsW(), layout.viewPixelsH());
  explore_.touch();
  if (docking && opened_) reframe();  // a panel docked or undocked: the view's shape changed
}

bool DesktopModel::select(std::uint16_t label, Framing framing) {
  const bool changed = explore_.selected() != label;
  if (!explore_.select(label)) return false;
  event({{"event", "select"}, {"label", label}, {"structure", idOf(label)}});
  if (changed && framing == Framing::kBringIntoView &&
      explore_.bringIntoView(label, layout_.viewPixelsW(), layout_.viewPixelsH()))
    event({{"event", "framed"}, {"structure", idOf(label)}});
  return true;
}

Status DesktopModel::setView(const std::string& name) {
  return explore_.setView(name, layout_.viewPixelsW(), layout_.viewPixelsH());  // the view beside the panel
}

void DesktopModel::reframe() {
  if (auto st = setView(explore_.viewName().empty() ? startView_ : explore_.viewName()); !st) message(st.error().message);
}

void DesktopModel::setExpert(bool on) {
  if (!on) {
    expert_->stop();
  } else {
    const std::uint16_t label = explore_.shownLabel();
    render::Preset p = explore_.presetOf(label, explore_.bare());
    p.t = explore_.t();
    expert_->start(p, idOf(label), [this, label](render::RenderMode mode) { return explore_.presetInMode(label, mode); });
  }
  expertEdited();
}

void DesktopModel::expertEdited() {
  explore_.setPresetOverride(expert_->active() ? std::optional<render::Preset>(expert_->preset()) : std::nullopt,
                             expert_->revision());
}

// ---------------------------------------------------------------------------------------------
// Frames

void DesktopModel::syncStudyView() {
  const auto shown = study_->shown();
  if (!shown) return;
  if (expertOn()) setExpert(false);  // the trial's presets, not an edited one
  const Structure* s = dataset_->findStructure(shown->structure);
  if (!s || !explore_.hasStructure(s->label)) return;  // loadStudyPresets and the dataset disagree: view unchanged
  explore_.usePreset(s->label, shown->preset, float(shown->t));
  if (explore_.selected() != s->label || explore_.hovered()) {
    setHovered(0);
    explore_.select(s->label);
    if (auto st = setView(shown->preset.view.value_or("lateral_left")); !st) message(st.error().message);
  }
}

void DesktopModel::beginFrame(FieldTarget* target) {
  recorder_.beginFrame();
  frameRenderMs_ = 0;
  syncStudyView();
  lessons_->poll();
  exams_->poll();
  study_->stepExport();
  imports_->poll();
  for (const std::string& line : classEvents_->takeLines()) message(line);
  segment_->poll();
  showEditedLabels();
  courses_->poll();
  if (!study_->participantActive())  // the participant's trial keeps its dataset
    if (auto imported = imports_->takeDatasetToOpen()) {
      const std::string id = imported->id;
      if (auto st = showDataset(std::move(*imported), "", ""); !st) {
        message("opening '" + id + "': " + st.error().message);
        imports_->openFailed("Opening '" + id + "' in the explore view failed: " + st.error().message);
      }
    }
  expertEdited();
  prefetchLessonFields();
  // On the CPU a prefetch and the software renderer share the cores: none starts until the view
  // on screen has converged (the student is reading), so that it does not slow the image down.
  fields_->holdPrefetches(viewAvailable_ && !scheduler_.finished(explore_.revision()));
  fields_->update(target, recorder_);
  if (fieldUnits_.poll()) explore_.touch();  // the shown field's own unit arrived: render again
  turnTowardTarget();
}

std::optional<RenderPlan> DesktopModel::planFrame(Clock::time_point now) {
  // Scripted screenshots outside a measured sweep render full quality at the render scale.
  const bool full = options_.scripted && !recorder_.recording();
  return scheduler_.plan(explore_.revision(), explore_.activity(), now, full);
}

render::FieldScale DesktopModel::fieldScaleOf(const ExploreState::Shown& shown, const render::StructureFrame& frame) const {
  render::FieldScale bySize;
  bySize.distanceUnit = render::distanceUnitFor(frame);
  std::shared_ptr<const DistanceField> field = fields_ ? fields_->shownField() : nullptr;
  if (!field || explore_.fieldLabel() != shown.label) return bySize;
  // Once per field, data TF and framed view (not while orbiting): rays through the framed view.
  // The view counts only for the modes whose unit comes from the bone it sees (field_scale.h),
  // measured as render::applyFieldScale measures it for the render command (measureFieldUnit).
  FieldUnitRequest request;
  request.key.field = field.get();
  request.key.label = shown.label;
  request.key.bone = render::boneLevels(shown.preset);
  request.key.mode = shown.preset.mode;
  request.key.seen = render::unitFromSeenBone(shown.preset.mode);
  request.key.view = {explore_.framedCamera(), explore_.framedPixels()[0], explore_.framedPixels()[1],
                      explore_.clipPlane()};
  if (render::judgedOnPicture(shown.preset.mode)) {  // fuzzy's and outline's unit, lighting's reach: judged on the picture
    request.key.picturePreset = shown.preset;
    request.key.picturePreset.t = 0;
    request.labels = &dataset_->labels;
    request.gradients = &gradients_;
  }
  request.field = std::move(field);
  request.volume = &dataset_->volume;
  request.frame = frame;
  return fieldUnits_.unitFor(request).value_or(bySize);
}

render::RenderSettings DesktopModel::renderSettings(const RenderPlan& plan) const {
  render::RenderSettings s;
  const ExploreState::Shown shown = explore_.shown();
  s.preset = shown.preset;
  s.camera = explore_.camera();
  // The distance unit from the shown field (render/field_scale.h), as the render command sets it;
  // until the field is there, from the structure's size.
  if (const render::StructureFrame* frame = explore_.frameOf(shown.label)) {
    const render::FieldScale scale = fieldScaleOf(shown, *frame);
    s.distanceUnit = scale.distanceUnit;
    s.distanceOffset = scale.distanceOffset;
    s.lightingReach = scale.lightingReach;
  }
  s.width = plan.width;
  s.height = plan.height;
  s.stepMm = render::effectiveStepMm(dataset_->volume.geometry, render::RenderSettings{}) * plan.stepFactor;
  s.shading = plan.shading;
  s.jitter = plan.jitter;
  s.background = {0.04f, 0.04f, 0.05f, 1.0f};
  s.clip = explore_.clipPlane();
  // The whole volume's data TF states its opacities per this length of ray (volume_preset.h).
  if (explore_.wholeVolume()) s.opacityRefMm = render::wholeVolumeRefMm(dataset_->volume.geometry);
  return s;
}

void DesktopModel::rendered(const RenderPlan& plan, double ms) {
  lastRenderFailure_.clear();
  scheduler_.rendered(plan, ms);
  recorder_.noteRender(plan.level, ms);
  frameRenderMs_ += ms;
}

bool DesktopModel::refined(const RenderPlan& plan, const RefineReport& report, double ms, Clock::time_point now) {
  recorder_.noteRefine(ms);
  lastRenderFailure_.clear();
  frameRenderMs_ += ms;
  const bool show = scheduler_.refined(plan, report, now);
  if (report.complete && scheduler_.settledAfterMs()) recorder_.noteSettled(*scheduler_.settledAfterMs(), double(plan.width) / std::max(1, layout_.viewPixelsW()));
  return show;
}

void DesktopModel::renderFailed(const std::string& why) {
  if (why != lastRenderFailure_)
    message("the 3-D view could not draw a frame (" + why +
            "); it starts over. If this keeps coming back, run with AT_GL_DEBUG=1 to see which GL call fails.");
  lastRenderFailure_ = why;
  scheduler_.failed();
}

void DesktopModel::endFrame(Clock::time_point end, double ms) {
  if (viewAvailable_ && study_->participantActive()) {  // what the participant sees, for their ratings
    const ExploreState::Shown shown = explore_.shown();
    StudyController::ViewQuality q;
    q.structure = idOf(shown.label);
    q.presetId = shown.preset.id.value_or("");
    q.mode = shown.preset.mode;
    q.level = scheduler_.showing(explore_.revision()) ? scheduler_.renderedLevel() : -1;
    q.fullLevel = kFullLevel;
    q.scale = scheduler_.fullScale() * options_.renderScale;
    q.settledMs = scheduler_.settledAfterMs();
    study_->noteViewQuality(q);
  }
  const std::uint16_t onScreen = explore_.bare() ? explore_.shownLabel() : explore_.fieldLabel();
  recorder_.frameShown(!viewAvailable_ || scheduler_.showing(explore_.revision()), onScreen, end);
  recorder_.endFrame(ms, scheduler_.interacting());
  scheduler_.frameTook(ms, frameRenderMs_);
}

bool DesktopModel::settled() const {
  const bool labelsShown = !segment_->attached() || segment_->labelsRevision() == editorLabelsRevision_;
  return labelsShown && (!viewAvailable_ || scheduler_.finished(explore_.revision())) && fields_->settled() &&
         !fieldUnits_.measuring() && !turnToward_;
}

bool DesktopModel::idle() const {
  return !options_.scripted && (!viewAvailable_ || scheduler_.finished(explore_.revision())) && !fields_->busy() &&
         !fields_->uploading() && !fieldUnits_.measuring();
}

}  // namespace at::app
