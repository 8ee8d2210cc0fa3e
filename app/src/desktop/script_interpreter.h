// The one UI-script interpreter (--ui-script FILE.json): {"actions": [{"do": "select", "structure":
// "cochlea"}, …]} replayed one action after another, each through the same DesktopModel commands
// the widgets use; the events the commands emit are the script's output (one JSON line each).
//
// Actions (arguments in the README and `anatomy-tutor desktop --help`):
//   view:     select, t, mode, view, hover, hover_structure, click, click_structure, orbit, zoom, clip,
//             expert, cancel_field (hover and click at {x, y} or at {view_at: [fx, fy]} of the view)
//   waiting:  wait {ms}, wait_field {timeout_ms} (the view settled: final quality, the field shown)
//   output:   screenshot {path}, widgets, record {on}, report {out}, hover_sweep {dwell_ms, out}, layout
//   lessons:  lesson_user, lessons, lesson, lesson_next, lesson_back, show_me {slice},
//             lesson_review_item {index, slice}, answer, review, lesson_close
//   exams:    exams, exam, exam_item, exam_answer, slice_click, slice_click_structure, exam_finish,
//             exam_leave, exam_review_item {index, slice}
//   analytics: analytics {course, group, tab} (the Class analytics window on that class), analytics {close}
//   expert:   tf_add_point, tf_move_point, tf_delete_point, tf_colour, preset_set, preset_save
//   studies:  study_start, study_toggle, study_rate, study_comment, study_next, study_close,
//             coordinator_open, coordinator_export, coordinator_summary
//   import:   import, cancel_import, open_imported
//   segment:  segment_open, segment_label, segment_slice, segment_seed, segment_grow, segment_undo,
//             segment_redo, segment_review, segment_tool, segment_clear_seeds, segment_save,
//             segment_threshold, segment_margin, segment_hollow
//   slices:   slices_open
//   courses:  course_new, course_open, course_lesson, course_show, course_question, course_step,
//             course_save, course_export, course_open_package, open_dataset
// An action that waits (a lesson being prepared, an import, an export, a locate answer's distance
// field, a new study screen until a window has shown it) is asked again next frame. A malformed or failing action ends the script with status 2,
// something waited for that never came (a timeout) with status 1.
#pragma once

#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "desktop_model.h"

namespace at::app {

// What the interpreter needs from the window it runs in.
class ScriptHost {
 public:
  virtual ~ScriptHost() = default;
  // Saves the window as PNG at `path` once the current frame is drawn.
  virtual void requestScreenshot(const std::string& path) = 0;
  // A requested screenshot has not been written yet.
  virtual bool screenshotPending() const = 0;
  // For the report: "800x480" and the GL context's description.
  virtual std::string windowText() const = 0;
  virtual std::string glText() const = 0;
  // The host draws the panels (a window): an action that changes a panel's screen waits until
  // the new screen is on display, whatever the frame rate (false: nothing is drawn, no wait).
  virtual bool drawsPanels() const = 0;
  // Where the last frame drew the widgets the panels name, and how many frames were drawn
  // ({"frame": n, "widgets": {…}}, ui/widget_rects.h); none without a window.
  virtual nlohmann::json widgetRects() const { return {{"frame", 0}, {"widgets", nlohmann::json::object()}}; }
};

class ScriptInterpreter {
 public:
  // Reads {"actions": [...]} from `path`; errors name the file and the problem.
  static Result<ScriptInterpreter> load(const std::string& path, std::optional<std::string> finalScreenshot);
  // `actions`: the list; `finalScreenshot`: saved once the actions are done and the view settled.
  ScriptInterpreter(std::vector<nlohmann::json> actions, std::optional<std::string> finalScreenshot);

  // Runs actions until one has to wait or the script ends; once per frame.
  void step(DesktopModel& model, ScriptHost& host, Clock::time_point now);
  bool finished() const { return finished_; }
  // 0 when every action worked; 2 for a malformed or failing action; 1 for a timeout.
  int exitStatus() const { return status_; }
  // The screenshot failed to be written: the script ends with status 1.
  void screenshotFailed(const std::string& why, DesktopModel& model);

  // Every action's name, for --help and tests.
  static std::vector<std::string> actionNames();

 private:
  enum class Progress { Done, Running };
  using Outcome = Result<Progress>;
  struct Context {
    DesktopModel& model;
    ScriptHost& host;
    const nlohmann::json& action;
    bool first;          // the action's first call
    double elapsedMs;    // since its first call
    Clock::time_point startedAt;  // its first call
  };
  using Handler = Outcome (ScriptInterpreter::*)(Context&);
  static const std::map<std::string, Handler>& handlers();
  void finish(int status);

  // The view (script_interpreter.cpp)
  Outcome select(Context&);
  Outcome setT(Context&);
  Outcome mode(Context&);
  Outcome view(Context&);
  Outcome hover(Context&);
  Outcome layout(Context&);
  Outcome click(Context&);
  Outcome hoverStructure(Context&);
  Outcome clickStructure(Context&);
  Outcome orbit(Context&);
  Outcome zoom(Context&);
  Outcome clip(Context&);
  Outcome expert(Context&);
  Outcome cancelField(Context&);
  Outcome wait(Context&);
  Outcome waitField(Context&);
  Outcome screenshot(Context&);
  Outcome widgets(Context&);  // [widgets] the window's size and ScriptHost::widgetRects
  Outcome record(Context&);
  Outcome report(Context&);
  Outcome hoverSweep(Context&);
  // The panels (script_actions_panels.cpp)
  Outcome lessonUser(Context&);
  Outcome lessonList(Context&);
  Outcome lesson(Context&);
  Outcome lessonNext(Context&);
  Outcome lessonReview(Context&);  // lesson_back, show_me, lesson_review_item {"index": i}; "slice": true
  Outcome answer(Context&);
  Outcome review(Context&);
  Outcome lessonClose(Context&);
  // Exams (script_actions_exam.cpp)
  Outcome examList(Context&);
  Outcome exam(Context&);
  Outcome examItem(Context&);
  Outcome examAnswer(Context&);
  Outcome sliceClick(Context&);
  Outcome sliceClickStructure(Context&);
  Outcome examFinish(Context&);
  Outcome examReviewItem(Context&);  // {"index": i, "slice": false}
  Outcome examLeave(Context&);
  Outcome analytics(Context&);  // script_actions_analytics.cpp
  Outcome tfEdit(Context&);
  Outcome presetSet(Context&);
  Outcome presetSave(Context&);
  Outcome studyStart(Context&);
  Outcome study(Context&);
  Outcome studyRate(Context&);  // waits for the side on screen at full quality
  Outcome awaitStudyScreen(Context&);
  Outcome coordinatorOpen(Context&);
  Outcome coordinatorExport(Context&);
  Outcome coordinatorSummary(Context&);
  Outcome importDataset(Context&);
  Outcome cancelImport(Context&);
  Outcome openImported(Context&);
  // The segment editor (script_actions_segment.cpp)
  Outcome segmentOpen(Context&);
  Outcome segmentLabel(Context&);
  Outcome segmentSlice(Context&);
  Outcome segmentSeed(Context&);
  Outcome segmentGrow(Context&);
  Outcome segmentUndo(Context&);
  Outcome segmentRedo(Context&);
  Outcome segmentReview(Context&);
  Outcome segmentTool(Context&);
  Outcome segmentClearSeeds(Context&);
  Outcome segmentSave(Context&);
  Outcome segmentThreshold(Context&);
  Outcome segmentMargin(Context&);
  Outcome segmentHollow(Context&);
  Outcome slicesOpen(Context&);
  // The course editor (script_actions_course.cpp)
  Outcome courseNew(Context&);
  Outcome courseOpen(Context&);
  Outcome courseLesson(Context&);
  Outcome courseShow(Context&);
  Outcome courseQuestion(Context&);
  Outcome courseStep(Context&);
  Outcome courseSave(Context&);
  Outcome openDataset(Context&);

  std::deque<nlohmann::json> actions_;
  std::optional<std::string> finalScreenshot_;
  bool begun_ = false;
  std::uint64_t widgetsAfterFrame_ = 0;  // "widgets": report a frame drawn after this one
  nlohmann::json widgetsLast_;           // ... whose rectangles agree with the frame before
  Clock::time_point actionStart_;
  bool finished_ = false;
  int status_ = 0;
};

}  // namespace at::app
