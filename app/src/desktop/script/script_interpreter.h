// The one UI-script interpreter (--ui-script FILE.json): {"actions": [{"do": "select", "structure":
// "cochlea"}, …]} replayed one action after another, each through the same DesktopModel commands
// the widgets use; the events the commands emit are the script's output (one JSON line each).
//
// The actions are registered by feature, each feature's table beside its handlers
// (script_actions_<feature>.cpp): name, arguments, one line of help and handler. That table is the
// one source of `anatomy-tutor desktop --help-actions` (and `--help ACTION`) and of
// docs/guide/ui-script-actions.md. An action that waits (a lesson being prepared, an import, an
// export, a locate answer's distance field, a new study screen until a window has shown it) is
// asked again next frame. A malformed or failing action ends the script with status 2, something
// waited for that never came (a timeout) with status 1.
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

// One argument of a UI-script action: its JSON key ("?" at its end: it may be left out) and what it
// holds (its default when optional).
struct ScriptArgument {
  std::string key;
  std::string what;
  bool optional() const { return !key.empty() && key.back() == '?'; }
  std::string name() const { return optional() ? key.substr(0, key.size() - 1) : key; }
};

// A UI-script action as documented: the feature (desktop area) that registers it, its name, its
// arguments and what it does.
struct ScriptActionDoc {
  std::string feature;
  std::string featureSummary;
  std::string name;
  std::vector<ScriptArgument> arguments;
  std::string help;
};

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

  // Every action the interpreter dispatches, by name.
  static std::vector<std::string> actionNames();
  // Every registered action, feature by feature in the registry's order (script_action_docs.cpp).
  static std::vector<ScriptActionDoc> actionDocs();
  // The actions as `desktop --help-actions` prints them (plain text), as Markdown tables
  // (docs/guide/ui-script-actions.md is this text), and one action's entry (nullopt: no such action).
  static std::string actionsText();
  static std::string actionsMarkdown();
  static std::optional<std::string> actionText(const std::string& name);
  // The one-line message for an action its handler could not read (`error`: nlohmann's type or
  // range error): the documented required arguments it leaves out, or else that error, then the
  // arguments the action takes and where they are described (desktop --help NAME).
  static std::string malformedActionMessage(const nlohmann::json& action, const std::string& name, const std::string& error);

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
  struct Action {
    const char* name;
    std::vector<ScriptArgument> arguments;
    const char* help;
    Handler handler;
  };
  struct Feature {
    const char* name;
    const char* summary;
    std::vector<Action> actions;
  };
  // Each feature's actions, defined in its script_actions_<feature>.cpp beside the handlers.
  static Feature viewActions();
  static Feature outputActions();
  static Feature lessonActions();
  static Feature examActions();
  static Feature analyticsActions();
  static Feature expertActions();
  static Feature studyActions();
  static Feature importActions();
  static Feature segmentActions();
  static Feature courseActions();
  // The features in the order the help lists them; the dispatch table built from them.
  static const std::vector<Feature>& features();
  static const std::map<std::string, Handler>& handlers();
  void finish(int status);

  // The view (script_actions_view.cpp)
  Outcome select(Context&);
  Outcome setT(Context&);
  Outcome mode(Context&);
  Outcome view(Context&);
  Outcome hover(Context&);
  Outcome click(Context&);
  Outcome hoverStructure(Context&);
  Outcome clickStructure(Context&);
  Outcome orbit(Context&);
  Outcome zoom(Context&);
  Outcome clip(Context&);
  Outcome cancelField(Context&);
  // Waiting and output (script_actions_output.cpp)
  Outcome wait(Context&);
  Outcome waitField(Context&);
  Outcome screenshot(Context&);
  Outcome widgets(Context&);  // [widgets] the window's size and ScriptHost::widgetRects
  Outcome layout(Context&);
  Outcome record(Context&);
  Outcome report(Context&);
  Outcome hoverSweep(Context&);
  // Lessons (script_actions_lessons.cpp)
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
  // The Class analytics window (script_actions_analytics.cpp)
  Outcome analytics(Context&);
  // The expert panel (script_actions_expert.cpp)
  Outcome expert(Context&);
  Outcome tfEdit(Context&);
  Outcome presetSet(Context&);
  Outcome presetSave(Context&);
  // Studies (script_actions_studies.cpp)
  Outcome studyStart(Context&);
  Outcome study(Context&);
  Outcome studyRate(Context&);  // waits for the side on screen at full quality
  Outcome awaitStudyScreen(Context&);
  Outcome coordinatorOpen(Context&);
  Outcome coordinatorExport(Context&);
  Outcome coordinatorSummary(Context&);
  // Imports (script_actions_import.cpp)
  Outcome importDataset(Context&);
  Outcome cancelImport(Context&);
  Outcome openImported(Context&);
  // The segment editor (script_actions_segment.cpp)
  Outcome segmentOpen(Context&);
  Outcome segmentLabel(Context&);
  Outcome segmentSeeds(Context&);
  Outcome segmentSlice(Context&);
  Outcome segmentSeed(Context&);
  Outcome segmentGrow(Context&);
  Outcome segmentGrowth(Context&);
  Outcome segmentSystem(Context&);
  Outcome segmentUndo(Context&);
  Outcome segmentRedo(Context&);
  Outcome segmentReview(Context&);
  Outcome segmentTool(Context&);
  Outcome segmentClearSeeds(Context&);
  Outcome segmentSave(Context&);
  Outcome segmentThreshold(Context&);
  Outcome segmentMargin(Context&);
  Outcome segmentHollow(Context&);
  Outcome segmentSplit(Context&);
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
