// The desktop's panels: they only draw, from the model's state, and call the model's and the
// controllers' commands — the same commands the UI script drives (script_interpreter.h). What a
// panel keeps is what only a widget needs: text being typed, a drag in progress, a GL texture.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "analytics/analytics_controller.h"
#include "desktop_model.h"
#include "render/gl/window_target.h"

namespace at::app {

// The orientation marker and the scale bar over the volume view, whose rectangle in window
// coordinates is (left, top, width, height) (view_overlay.cpp).
void drawViewOverlay(const render::Camera& camera, float left, float top, float width, float height, float uiScale);

// Practical exams inside the lesson runner: the course's exams, an attempt (items, the clock, no
// names or grades), the results; and the CT slice of a locate-on-slice item over the volume view.
class ExamPanel {
 public:
  void drawList(ExamController& exams);
  // True while it takes the lesson runner's place (an exam preparing, running or its results).
  bool active(const ExamController& exams) const;
  void draw(ExamController& exams);
  // Over the volume view (x, y, w, h in window coordinates) while a slice item is on screen.
  void drawSlice(DesktopModel& model, float x, float y, float w, float h);

 private:
  void drawItem(ExamController& exams);
  void drawResults(ExamController& exams);
  std::optional<render::gl::ImageTexture> slice_;
  std::uint64_t sliceRevision_ = 0;
  std::string sliceError_;
};

// The lesson runner inside the explore panel (courses and lessons, steps, questions, review, exams).
class LessonPanel {
 public:
  void draw(LessonController& lessons, ExamController& exams, float height);
  ExamPanel& exams() { return exams_; }

 private:
  void drawLists(LessonController& lessons);
  void drawLesson(LessonController& lessons);
  void drawQuestion(LessonController& lessons);
  void drawReview(LessonController& lessons);
  std::string userEdit_;
  bool editingUser_ = false;
  std::string scrolledTo_;  // the graded question the panel last scrolled down to (its feedback, Next)
  ExamPanel exams_;
};

// The left panel: dataset, lessons, the selected and hovered structure, preset mode and t, views,
// clipping plane, the structure browser, frame and field status and messages.
class ExplorePanel {
 public:
  struct Status {
    std::string glDescription;
  };
  void draw(DesktopModel& model, const Status& status);
  ExamPanel& exams() { return lessons_.exams(); }
  // Its width as last drawn (the user may drag its edge); 0 before the first frame.
  float width() const { return width_; }

 private:
  void drawStructures(DesktopModel& model, bool hideNames);
  void drawFieldProgress(DesktopModel& model);
  void drawQuality(DesktopModel& model);
  float statusHeight(const DesktopModel& model) const;
  std::string search_;
  LessonPanel lessons_;
  float width_ = 0;
};

// The preference study: the blinded participant window (in place of the explore panel) and the
// coordinator window.
class StudyPanel {
 public:
  // Every text of the participant window goes through the label helpers; in scripted mode the
  // labels of each new participant screen (and the ImGui windows that were visible) are printed
  // as a "study_screen" event once it is on screen.
  void drawParticipant(StudyController& study, float width, float height);
  void drawCoordinator(StudyController& study, float x, float y);

 private:
  void text(const std::string& s);
  void textWrapped(const std::string& s);
  bool button(const std::string& label);
  bool radio(const std::string& label, int* value, int mine);
  void summaryTable(const StudyController& study);
  void summaryChart(StudyController& study);
  std::vector<std::string> labels_;   // texts drawn in the participant window this frame
  bool announce_ = false;             // print the next drawn participant screen
  std::string participantId_, outDir_ = "study_export";
  int groupIndex_ = 0;
  std::optional<render::gl::ImageTexture> chart_;
  std::uint64_t chartRevision_ = 0;
  std::string chartError_;
  std::string coordinatorError_;  // the last failed command of the coordinator window
};

// An opaque RGBA copy of an RGB picture, for an ImageTexture.
render::RgbaImage toRgba(const RgbImage& image);

// A slice picture in a pane (the Slices window's and the segment editor's): `texture` drawn at
// its voxels' aspect (`pixelMm`: mm of one picture pixel along columns and rows), its longer side
// `side` pixels, under an invisible button `id` that takes its clicks; a right drag over it is a
// grey-window drag given to `grey` (GreyWindow::drag's dx, dy). Returns the mouse in picture
// pixels while it hovers the picture.
// Where a panel is drawn, in logical pixels: docked (w, h > 0: that rectangle, fixed) or floating
// (w = h = 0: first placed at x, y, then moved and sized by the user).
struct PanelRect {
  float x = 0, y = 0, w = 0, h = 0;
  bool docked() const { return w > 0 && h > 0; }
};

// ImGui::Begin of a panel window at `where`: docked (fixed, neither moved nor resized) or floating
// (placed when it appears, sized to fit). False when collapsed: the caller still calls End().
bool beginPanel(const char* title, bool* open, const PanelRect& where);

struct PaneMouse {
  double x = 0, y = 0;
};
// The layout's patient direction letters (L R A P S I) at the middle of the last item's four edges,
// inside the picture (the Slices panes, the exam and answer slice).
void drawEdgeLetters(const SliceLayout& layout);
std::optional<PaneMouse> drawSlicePane(const char* id, const render::gl::ImageTexture& texture, std::array<double, 2> pixelMm,
                                       float side, const std::function<void(double, double)>& grey);

// The Slices window: sagittal, coronal and axial panes through the crosshair at their voxels'
// aspect, the segment editor's labels over them at an opacity; a left click moves the crosshair,
// a right drag sets the grey window.
class SlicesPanel {
 public:
  void draw(DesktopModel& model, const PanelRect& where);

 private:
  std::array<std::optional<render::gl::ImageTexture>, 3> textures_;
  std::array<std::uint64_t, 3> drawn_{~0ull, ~0ull, ~0ull};  // the key of each pane's picture
  std::string error_;
};

// The import window.
class ImportPanel {
 public:
  void draw(ImportController& imports, float x, float y);

 private:
  std::string error_;  // an import that could not start
};

// The segment editor's window: labels, a slice to paint seeds in (right drag: grey window), grow,
// undo / redo and save, in collapsible sections; docked as a column at the window's right edge
// when the layout has one (dockPanels), else floating.
class SegmentPanel {
 public:
  void draw(SegmentController& editor, const PanelRect& where);

 private:
  void report(const Status& st);  // the error shown under the controls, or none
  void drawLabels(SegmentController& editor, int listLines);
  void drawLabelGrowRange(SegmentController& editor, std::uint16_t label);
  void drawSliceControls(SegmentController& editor);
  void drawSlice(SegmentController& editor, float side);  // the picture, its longer side `side` px
  void drawTools(SegmentController& editor);
  void drawGrowthSettings(SegmentController& editor);
  void drawSaving(SegmentController& editor);
  std::optional<render::gl::ImageTexture> texture_;
  std::uint64_t revision_ = 0;
  std::optional<std::array<int, 3>> lastPainted_;  // the voxel under a drag (one paint per voxel)
  bool stroking_ = false;          // a paint / erase drag in the slice is under way
  float range_[2] = {0, 0};        // the island's value range (dataset units), from its window
  bool rangeSet_ = false;
  // In mm at a scale of 1 (CT, a 0.1 mm µCT); shown and applied times the editor's brushScale, so
  // on a finer µCT they keep their voxels as the brush does.
  float minDiameterMm_ = 0;
  float marginMm_ = 1.0f;          // margin grow/shrink and hollow thickness
  std::string newLabel_, exportPath_, error_, seedsPath_ = "seeds.json";
  std::string system_;          // the system field of the current structure (edited, not yet applied)
  int systemLabel_ = -1;        // the structure system_ was read from
};

// The course editor window (instructors): a new course on the dataset on screen, a stored one to
// edit, or Open course… (a package); lessons, steps captured from the view, questions, live
// problems, save and export. Also the Dataset menu's list in the explore panel.
class CourseEditorPanel {
 public:
  void draw(DesktopModel& model, float x, float y);

 private:
  void drawStart(DesktopModel& model);
  void drawCourse(DesktopModel& model);
  void drawSteps(DesktopModel& model);
  void drawPreview(DesktopModel& model);
  void drawAddStep(DesktopModel& model);
  void report(const Status& st, const std::string& done);
  std::string newId_ = "my_course", newTitle_, openPath_, openVolume_, lessonTitle_;
  std::string showTitle_, showText_, prompt_, synonyms_, candidates_, exportPath_ = "course.atcourse", note_;
  int kind_ = 0, target_ = 0, other_ = 0, courseChoice_ = 0;
  float toleranceMm_ = 0;
  bool onView_ = false, reference_ = false;
  bool checking_ = false;  // the editor was checking a locate question when last drawn
  std::string status_;
  bool failed_ = false;
};

// The expert panel at the window's right edge: spline editors for the data TF (over the HU
// histogram) and the distance TF, the preset's other parameters and "Save as".
class ExpertPanel {
 public:
  // True when the preset changed.
  bool draw(TfEditor& editor, float x, float width, float height);

 private:
  struct Selection {
    bool data = true;
    std::size_t index = 0;
  };
  bool splineEditor(TfEditor& editor, const char* id, bool data, float width, float height);
  std::optional<Selection> dragging_, menuFor_;
  std::string saveName_ = "my_preset", exportPath_, saveStatus_;
};

// The Class analytics window (instructors), placed at (x, y) with (width, height) when it opens.
class AnalyticsPanel {
 public:
  void draw(AnalyticsController& analytics, float x, float y, float width, float height);

 private:
  void drawStructures(const AnalyticsController& analytics);
  void drawMissed(const AnalyticsController& analytics);
  void drawStudents(const AnalyticsController& analytics);
  void drawLessons(const AnalyticsController& analytics);
  void report(const Status& st);
  std::optional<std::vector<AnalyticsController::CourseChoice>> courses_;  // while the window is open
  std::string error_;  // the last failed load
};

}  // namespace at::app
