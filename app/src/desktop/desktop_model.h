// The desktop app's logic, with no SDL, GL or ImGui in it: the dataset on screen, the explore
// state, its distance fields, the frame scheduler and recorder, and the controllers of the lesson,
// study, import, expert and segment panels — and the commands that the widgets and the UI script both use
// (hover, click, select, views, expert on/off, …). The window shell (ui/) feeds it input and a
// layout, renders what it plans, and draws the panels from its state; tests drive it without any
// window (no FieldTarget, no view: picking and fields still run on the CPU).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "class_sync.h"
#include "core/error.h"
#include "analytics/analytics_controller.h"
#include "exams/exam_controller.h"
#include "view/explore_state.h"
#include "view/field_unit.h"
#include "view/field_view.h"
#include "view/frame_scheduler.h"
#include "course_editor/course_editor.h"
#include "import/import_controller.h"
#include "learning_session.h"
#include "scan_volumes.h"
#include "lesson_player/lesson_controller.h"
#include "render/field_scale.h"
#include "render/gradient_volume.h"
#include "render/render_settings.h"
#include "render/structure_pick.h"
#include "view/slice_views.h"
#include "studies/study_controller.h"
#include "expert/tf_editor.h"
#include "volume/png_image.h"
#include "volume/slice_image.h"

namespace at::app {

// Where the volume view lies in the window: right of the explore panel, left of a docked column
// (the segment editor) and above a docked strip (the slice panes), when those are docked.
struct ViewLayout {
  int windowW = 1280, windowH = 720;          // logical pixels (mouse coordinates)
  int framebufferW = 1280, framebufferH = 720;  // drawable pixels
  float uiScale = 1;
  float panelPx = 0;                            // the explore panel's width as drawn (resizable); 0: the default
  float rightPx = 0;                            // the segment editor's column docked right of the view (logical pixels)
  float expertPx = 0;                           // the expert panel's column at the window's right edge (logical pixels)
  float bottomPx = 0;                           // a strip docked under the view, left of those columns
  float panelWidth() const { return panelPx > 0 ? panelPx : 320 * uiScale; }  // logical pixels
  // The view's rectangle in logical pixels.
  float viewLeft() const { return panelWidth(); }
  float viewWidth() const { return std::max(1.0f, float(windowW) - panelWidth() - rightPx - expertPx); }
  float viewHeight() const { return std::max(1.0f, float(windowH) - bottomPx); }
  bool inView(double x, double y) const {
    return x >= viewLeft() && x < viewLeft() + viewWidth() && y >= 0 && y < viewHeight();
  }
  // The view's size in framebuffer pixels.
  int viewPixelsW() const;
  int viewPixelsH() const;
  bool operator==(const ViewLayout&) const = default;
};

// Docks the expert panel (`expert` open) as a column at the window's right edge, the segment editor
// (`editor` open) as a column left of it, and the slice panes (`slices` open too) as a strip under
// the view, each when the window is wide enough for the view to keep kMinDockedViewPx beside them
// (1280 × 720 and larger at UI scale 1, the expert panel and the editor together from about 1500);
// otherwise they stay windows over the view and the layout keeps the view whole. A docked panel
// never covers the view, so the structure framed in its centre stays in sight.
inline constexpr float kMinDockedViewPx = 400;
inline constexpr float kExpertPanelPx = 340;  // the expert panel's width at UI scale 1
void dockPanels(ViewLayout& layout, bool editor, bool slices, bool expert = false);

struct DesktopOptions {
  std::string dataset;              // empty: the start course's dataset; else as openNamedDataset takes it
  std::string course;               // the course to start on (its first lesson's first view); empty: the default
  std::string userName = kDefaultLessonUser;  // whose lesson progress the lesson panel shows and records
  double renderScale = 1;           // resolution of the full-quality level (slow software GL: < 1)
  double frameBudgetMs = 100;       // at rest, finer levels predicted to cost more are not rendered
  bool scripted = false;            // a UI script drives the app: events are printed, screenshots at full quality
  bool prefetchLessonFields = true; // a lesson's next steps' fields computed while the student reads
  // How the shown field's distance unit is measured (empty: measureFieldUnit). On a worker thread
  // unless scripted (view/field_unit.h).
  FieldUnitMeasure measureFieldUnit;
};

class SegmentController;

class DesktopModel {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  using MessageSink = std::function<void(const std::string&)>;
  // `session` and `library` outlive the model. `events`: scripted-mode events. Messages for the
  // user go to stderr, to the explore panel (the last six) and to `messages` when given.
  DesktopModel(LearningSession& session, const render::PresetLibrary& library, DesktopOptions options, EventSink events,
               MessageSink messages = {});
  ~DesktopModel();

  // Opens the start dataset (options' or the default course's, on its first lesson's first view).
  Status open();
  // Shows `dataset` in the explore view (an imported one opened), starting on `startStructure`
  // when it has one; an error leaves the current dataset on screen.
  Status showDataset(Dataset dataset, const std::string& startStructure, const std::string& startPreset);
  const Dataset& dataset() const { return *dataset_; }
  // The datasets the dataset menu offers: the phantom, the skull CT when its file is here, and
  // every imported dataset (by name).
  std::vector<std::string> datasetChoices();
  // Opens the dataset called `name` (as openNamedDataset takes it) in the view [open_dataset].
  Status switchDataset(const std::string& name);
  // The dataset's gradient volume: shading (the renderer) and picking share it.
  const render::GradientVolume& gradients() const { return gradients_; }
  // Changes whenever another dataset is shown (the renderer uploads its volume then).
  std::uint64_t datasetRevision() const { return datasetRevision_; }
  // The segment editor's labels reach the dataset on screen at the start of each frame after an
  // edit, undo or redo (showEditedLabels): `revision` moves then and `box` bounds the voxels
  // that changed ({x0, y0, z0, x1, y1, z1}, max exclusive), for the renderer to upload only those.
  struct LabelEdit {
    std::uint64_t revision = 0;
    std::array<int, 6> box{0, 0, 0, 0, 0, 0};
  };
  const LabelEdit& labelEdit() const { return labelEdit_; }

  ExploreState& explore() { return explore_; }
  const ExploreState& explore() const { return explore_; }
  FieldView& fields() { return *fields_; }
  const FieldView& fields() const { return *fields_; }
  FrameScheduler& scheduler() { return scheduler_; }
  FrameRecorder& recorder() { return recorder_; }
  LessonController& lessons() { return *lessons_; }
  ExamController& exams() { return *exams_; }
  AnalyticsController& analytics() { return *analytics_; }
  StudyController& study() { return *study_; }
  ImportController& imports() { return *imports_; }
  TfEditor& expert() { return *expert_; }
  SegmentController& segmenter() { return *segment_; }
  CourseEditor& courseEditor() { return *courses_; }
  // The three slice panes; a click in the 3-D view that meets the volume moves their crosshair.
  SliceViews& slices() { return slices_; }
  const DesktopOptions& options() const { return options_; }

  // The window's layout (each frame); a new size re-renders the view.
  void setLayout(const ViewLayout& layout);
  const ViewLayout& layout() const { return layout_; }
  // Whether a volume view exists (GL 4.3 and a renderer); without one nothing waits for renders.
  void setViewAvailable(bool available) { viewAvailable_ = available; }

  // --- Commands ------------------------------------------------------------------------------
  void hoverAt(double x, double y);  // window coordinates; picks the structure under the cursor [hover]
  void clickAt(double x, double y);  // a locate answer, else selects what is under the cursor (not during an exam)
  // With the segment editor's paint or erase tool (SegmentController::brushesInView): one dab of
  // its brush where the ray through (x, y) meets the volume's first visible surface (nothing off
  // it); the slices' crosshair and the editor's slice move there. clickAt is a stroke
  // of one dab; a drag brackets its dabs with the editor's beginStroke / endStroke.
  void brushAt(double x, double y);
  void clearHover() { setHovered(0); }
  // [select] Selects the structure; from the list (kBringIntoView) a structure the view does not
  // show whole (or shows small) is framed from the side the view looks from
  // (ExploreState::bringIntoView); a click on it in the 3-D view (kKeepCamera) leaves the camera
  // where the user put it.
  enum class Framing { kBringIntoView, kKeepCamera };
  bool select(std::uint16_t label, Framing framing = Framing::kBringIntoView);
  Status setView(const std::string& name);
  // The current named view again (the start view before any), framed for the layout now.
  void reframe();
  void setExpert(bool on);           // opens the expert panel on the view's preset, or closes it
  void expertEdited();               // the expert's preset changed: the view follows it
  bool expertOn() const { return expert_->active(); }
  bool cancelFineField() { return fields_->cancelFineField(); }
  // Where a structure's centroid appears in the window (nullopt: outside the view).
  std::optional<std::array<double, 2>> projectStructure(std::uint16_t label) const;
  // A lesson step's structure, preset and view.
  void showLessonStructure(const LessonController::Shown& shown);
  // The step's structure drawn with `preset` (its t) from its named view, or its free camera, with
  // its clipping plane or none (a step as a student sees it).
  void showStructureWith(const LessonController::Shown& shown, const render::Preset& preset);
  // What the view shows now, for the course editor: the selected structure, its preset with the
  // view's t, the named view (the last one chosen), the camera and the clipping plane. An error
  // when nothing is selected.
  Result<CourseEditor::Capture> captureView() const;
  // The dataset id a course made on screen names: the dataset's, with the phantom at any size
  // ("phantom:128") named "phantom" (the same anatomy).
  std::string courseDatasetId() const;
  // Structure names must not be shown (a lesson question or an exam would be given away).
  bool namesHidden() const { return lessons_->namesHidden() || exams_->namesHidden() || previewHidesNames(); }
  // The course editor previews a question step as a student sees it (its structure still selected,
  // the editor open): names hidden as in the lesson.
  bool previewHidesNames() const;

  // --- Exams ----------------------------------------------------------------------------------
  // An exam item's view: its scene; for a locate item in the 3-D view, once the scene's field is
  // on screen, the first side (the scene's, then the other named views) from which a click on the
  // target's centre picks the target [exam_view]; for a locate item on a slice, the axial CT
  // slice through the target's centre (no labels). nullopt: the exam's view ends.
  void showExamItem(const std::optional<ExamController::ItemScene>& item);
  struct ExamSlice {
    SliceRequest request;
    RgbImage image;            // one pixel per voxel
    std::uint64_t revision = 0;
    // "Show me on a slice": the structure overlaid (alone, in its colour); empty for an exam
    // item's unlabelled slice. Such a slice answers nothing and is shown with the name.
    std::string highlighted;
  };
  const std::optional<ExamSlice>& examSlice() const { return examSlice_; }
  // A click at pixel (x, y) of the exam slice's image: answers the slice item.
  void clickSlice(double x, double y);
  // "Show me on a slice" (a lesson's show me and review, the exam review): the axial CT slice
  // through `structureId`'s anchor (its voxel nearest its centroid) with that structure alone
  // overlaid, shown in place of the 3-D view until closed or the next step or item [answer_slice].
  Status showAnswerSlice(const std::string& structureId);
  void closeAnswerSlice();
  // The slice pixel nearest the in-slice centre of `label`'s voxels on the exam slice (nullopt:
  // no slice, or the structure is not on it).
  std::optional<std::array<double, 2>> slicePixelOf(std::uint16_t label) const;
  // The render parameters on screen, stored with each lesson answer.
  lessons::RenderState renderState() const;

  // --- Frames ---------------------------------------------------------------------------------
  // Start of a frame: the study's trial view, an imported dataset to open, the controllers' work
  // (a lesson starting, an export's next file, an import's progress) and the fields, handed to
  // `target` (null: no view).
  void beginFrame(FieldTarget* target);
  // The image to render now, if any, and the settings to render it with.
  std::optional<RenderPlan> planFrame(Clock::time_point now);
  render::RenderSettings renderSettings(const RenderPlan& plan) const;
  void rendered(const RenderPlan& plan, double ms);
  // A progressive plan's refine call took `ms` and left the image as `report` says; whether the
  // view is to show the refined image now.
  bool refined(const RenderPlan& plan, const RefineReport& report, double ms, Clock::time_point now);
  void renderFailed(const std::string& why);
  // End of a frame that took `ms` (for the recorder and the highlight latency).
  void endFrame(Clock::time_point end, double ms);
  // The image is final (full quality), shows the field the view needs and the segment editor's
  // latest labels.
  bool settled() const;
  // Nothing changes until the user acts (the loop may wait for input).
  bool idle() const;

  void message(const std::string& text);
  const std::vector<std::string>& messages() const { return messages_; }
  // Neutral information (not a problem): shown apart from the messages, also on stderr.
  void note(const std::string& text);
  const std::vector<std::string>& notes() const { return notes_; }
  // What holds for the shown dataset as long as it is shown (its intensities are not attenuation:
  // services/intensity_notes.h), reported once as a note when it opens; empty: nothing.
  const std::optional<std::string>& datasetCaution() const { return datasetCaution_; }
  void event(nlohmann::json e) { events_(std::move(e)); }

 private:
  // A line for the user on stderr and to the message sink (the scripted mode's events).
  void report(const std::string& text);
  void setHovered(std::uint16_t label);
  // The editor's labels and structures into the dataset on screen when they changed: the voxels
  // that differ (the field service's labels, written while no field reads them), the structure
  // list, the explore state (frames, browser, selection of the edited structure) and the fields
  // of the labels that changed (desktop_model_segment.cpp). Event labels_shown {"changed": labels,
  // "box", "whole_volume", "selected", "ms": the time this took on the UI thread}.
  void showEditedLabels();
  // What a click at window (x, y) meets in the view as the image shows it.
  // surfaceOpacity: where the ray's accumulated opacity first reaches it (the surface a brush
  // paints on) instead of the structure under the cursor (render::pickStructure).
  render::PickResult pickAt(double x, double y, std::optional<double> surfaceOpacity = std::nullopt) const;
  // A locate answer clicked on `clicked` (null: nothing) at `pointMm` (if known): to the exam or
  // the lesson; off a target with a tolerance, graded once its distance is known.
  void answerLocate(const Structure* clicked, const std::optional<Vec3>& pointMm);
  void clickGraded(const std::string& clicked, double distanceMm);
  void turnTowardTarget();  // an exam locate item's view (showExamItem)
  // A running lesson's coming fields in the background while the student reads
  // (lessonFieldNeeds, FieldView::prefetch within its budget): every later step's view, each
  // question's answer key (locate) and show-me field, and the current step's view while it is
  // still being computed. A step's field is then there when the step is shown instead of seconds
  // later on the CPU. Asked again each time the step changes; dropped (and a running prefetch
  // cancelled) when no lesson runs (desktop_model_lessons.cpp).
  void prefetchLessonFields();
  std::string prefetchedFor_;  // the lesson and step the prefetch list was made for
  // The axial slice through `target`'s anchor; `highlight`: the target overlaid on it.
  Result<ExamSlice> anchorSlice(const Structure& target, bool highlight);
  void syncStudyView();  // participant mode: the trial's structure with the preset of the side shown
  std::string idOf(std::uint16_t label) const;

  LearningSession& session_;
  const render::PresetLibrary& library_;
  DesktopOptions options_;
  EventSink events_;
  MessageSink messageSink_;
  std::vector<std::string> messages_;
  std::vector<std::string> notes_;
  std::optional<std::string> datasetCaution_;
  std::unique_ptr<Dataset> dataset_;
  ShownScan shown_;  // dataset_'s volume as loaded, where showing it left out non-anatomy
  // The shown field's distance unit (render/field_scale.h), measured once per field and framed
  // view on a worker (synchronously when scripted); taken each frame in beginFrame. Declared after
  // dataset_: destroyed (its measure waited for) before the volume it reads.
  mutable FieldUnits fieldUnits_;
  // The shown field's distance unit and offset (render/field_scale.h); from the structure's size
  // until its field is there and its unit measured (meanwhile the last unit of the same structure).
  render::FieldScale fieldScaleOf(const ExploreState::Shown& shown, const render::StructureFrame& frame) const;
  render::GradientVolume gradients_;
  // The course editor's locate check on the dataset on screen (desktop_model_course.cpp): the
  // work to run on the editor's worker for one question. One checker per dataset shown (made at
  // its first check, dropped with the dataset), sharing gradients_ and keeping regions' fields
  // between checks; courses_, declared after it, is destroyed first and joins a running check.
  CourseEditor::LocateCheckWork locateCheckWork(const quiz::Question& question, const lessons::QuestionScene& scene,
                                                const render::Preset& preset);
  std::unique_ptr<LocateViewChecker> locateChecker_;
  std::uint64_t checkerLabelsRevision_ = 0;  // editorLabelsRevision_ when the checker took the labels
  mutable render::ShadingTableCache pickTables_;  // pickAt is const; the cache only saves work
  std::uint64_t datasetRevision_ = 0;
  std::uint64_t editorLabelsRevision_ = 0;  // the editor's labelsRevision() last shown
  LabelEdit labelEdit_;
  std::string startView_ = "lateral_right";
  bool opened_ = false;
  ExploreState explore_;
  std::unique_ptr<FieldView> fields_;
  FrameScheduler scheduler_;
  double frameRenderMs_ = 0;  // rendering in this frame
  std::string lastRenderFailure_;  // reported once until a render succeeds
  FrameRecorder recorder_;
  std::unique_ptr<TfEditor> expert_;
  std::unique_ptr<LessonController> lessons_;
  std::unique_ptr<ExamController> exams_;
  std::unique_ptr<AnalyticsController> analytics_;
  struct Turn {
    std::uint16_t target = 0;
    std::string view;  // the scene's own side, tried first
  };
  std::optional<Turn> turnToward_;
  std::optional<ExamSlice> examSlice_;
  std::uint64_t sliceRevision_ = 0;
  std::unique_ptr<StudyController> study_;
  std::unique_ptr<ImportController> imports_;
  std::unique_ptr<SegmentController> segment_;
  std::unique_ptr<CourseEditor> courses_;
  std::unique_ptr<BackgroundOutboxSender> classEvents_;  // the user's answers to their class server
  SliceViews slices_;
  ViewLayout layout_;
  bool viewAvailable_ = false;
  std::optional<Vec3> lastPickMm_;  // where the last hover pick met the volume (LPS mm)
};

}  // namespace at::app
