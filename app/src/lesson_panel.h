// The desktop app's lesson runner (issue 7): course and lesson lists with the user's progress and
// prerequisites, a lesson's steps through lessons::LessonEngine (so prerequisites are enforced and
// every answer is graded and committed to the database before its feedback shows), an input for
// every question kind (locate: a click in the 3-D view, handed over by the app), the lesson's
// score at the end, and a review section (the structures due, and an adaptive review question).
//
// The panel works through the app's learning session (learning_session.h: the same database,
// repositories, users and answer keys as `anatomy-tutor play`, so desktop and terminal progress
// are one) and owns the running lesson's engine. It never touches the
// view itself: what a step shows goes to the app through the `ShowStructure` callback, and while
// a question must not give its answer away (identify/name questions, quiz-only lessons)
// namesHidden() tells the app to hide structure names.
//
// Review answers go through lessons::answerReview: graded as lesson answers and committed with the
// structure's FSRS memory state, the review log and Elo before their feedback shows, so the review queue moves.
#pragma once

#include <chrono>
#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lessons/curriculum.h"
#include "lessons/lesson_engine.h"
#include "lessons/repositories.h"
#include "learning_session.h"
#include "quiz/question.h"
#include "core/error.h"

namespace at::app {

class LessonPanel {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  // What the view should show for a step: the structure (id) with a preset (id; empty = the
  // structure's WDT preset) from a named view (nullopt = keep the current camera direction).
  struct Shown {
    std::string structure;
    std::string presetId;
    std::optional<lessons::CameraView> view;
  };
  using ShowStructure = std::function<void(const Shown&)>;
  // The render parameters on screen, stored with each answer.
  using RenderStateSource = std::function<lessons::RenderState()>;

  // `session`: the app's learning session (it outlives the panel). `userName`: the pseudonymous
  // user, created as a student when first needed. `viewDataset`: the id of the dataset the view
  // shows (a course on another one gets a warning).
  LessonPanel(LearningSession& session, std::string userName, std::string viewDataset, EventSink events,
              ShowStructure show, RenderStateSource renderState);
  ~LessonPanel();
  // The view now shows another dataset (an imported one was opened).
  void setViewDataset(std::string id) { viewDataset_ = std::move(id); }

  // Draws the panel inside the current ImGui window (the app's left panel), in a scrolling
  // region `height` pixels high.
  void draw(float height);

  // The current step is a locate question not yet answered: a click in the view answers it.
  bool wantsClick() const;
  // The current locate question accepts clicks near its target (a tolerance in mm): a click off
  // the target needs its weighted distance from the target to be graded.
  bool wantsClickDistance() const;
  // A click in the 3-D view on `structure` ("" for none). `distanceMm`: the weighted distance of
  // the click from the question's target when known, else negative. Returns true when the click
  // answered a locate question (the app then does not treat it as a selection).
  bool clicked(const std::string& structure, double distanceMm = -1);
  // Structure names must not be shown anywhere while this is true.
  bool namesHidden() const;
  // The target of the current question (for the app to sample its distance field), if any.
  std::optional<std::string> questionTarget() const;

  // Scripted actions (events in brackets):
  //   "lesson_user" {name}        switches to (or creates) the user [lesson_user]
  //   "lessons" {course?}         the course's lesson list with progress and locks [lessons]
  //   "lesson" {course?, lesson, mode?: "guided"|"quiz_only"}  start or resume [lesson_started,
  //                               lesson_step; lesson_refused when locked, then an error]
  //   "lesson_next"               past the current step [lesson_step, or lesson_finished with the score]
  //   "answer" {value}            a choice (index, or a choice's id or name), a typed name, a list of
  //                               structures (order), or a `play --answers` object [graded]
  //   "review"                    [review_queue, review_question]; "answer" then answers it (the
  //                               graded event says review and recorded; the queue moves)
  //   "lesson_close"              leaves the lesson (answers are saved; "lesson" resumes it)
  // Locate questions are answered by "click"/"click_structure" in the app. Errors name the problem.
  static bool handled(const std::string& what);
  // Returns true when the action is done, false while it runs (a lesson being prepared: call
  // again next frame).
  Result<bool> scriptAction(const std::string& what, const nlohmann::json& action);

 private:
  struct Store;
  struct LessonRow {
    std::string id, title, summary;
    std::vector<std::string> missing;  // unfinished prerequisites (titles): locked when not empty
    int attempts = 0;
    bool open = false;                 // an unfinished attempt exists
    std::optional<double> bestScore;   // of finished attempts
    int questions = 0;
  };
  // A question being asked: the current lesson step's, or a review question.
  struct Asked {
    quiz::ResolvedQuestion question;
    std::vector<std::string> choiceNames;
    bool review = false;
    std::optional<quiz::Grade> grade;
    std::vector<std::string> order;     // Order: the student's sequence so far (ids)
    int choice = -1;                    // Identify/Relation: the selected choice
    std::string text;                   // Name: typed so far
    std::chrono::steady_clock::time_point shownAt = std::chrono::steady_clock::now();
  };

  Result<Store*> store();
  Status switchUser(const std::string& name);             // no lesson may be running
  Status refresh();                                       // courses, lesson rows, review queue
  // Starts the engine on a thread; pollStart() (each frame, and scripts) completes the start.
  Status startLesson(const std::string& lessonId, lessons::LessonMode mode);
  void pollStart();
  Status completeStart();                                 // the started engine becomes the lesson
  Result<bool> scriptStartLesson(const nlohmann::json& action);
  Status scriptStep(const std::string& what, const nlohmann::json& action);
  Status showCurrent();                                   // the engine's current step → view, asked_
  Status nextStep();                                      // past the current step (finishes at the end)
  Status finishLesson();                                  // stores the score, back to the lists
  Status startReview();
  Result<quiz::Grade> submit(const quiz::Answer& answer);  // grades and records (lesson or review)
  Result<quiz::Answer> answerFromScript(const nlohmann::json& value) const;
  std::string displayName(const std::string& structureId) const;
  void fail(const std::string& text);                     // shows the message in the panel

  void drawContent();
  void drawCourses();
  void drawLesson();
  void drawQuestion();
  void drawReview();

  LearningSession& session_;
  std::string userName_;
  std::string viewDataset_;
  EventSink events_;
  ShowStructure show_;
  RenderStateSource renderState_;
  std::unique_ptr<Store> store_;
  std::string storeError_;
  // A lesson being started (declared after store_: destroyed, that is joined, before it).
  struct Pending {
    std::unique_ptr<lessons::LessonEngine> engine;
    std::future<Status> started;
    std::string lessonId, courseId, title;
  };
  std::optional<Pending> pending_;
  std::optional<Status> startResult_;  // how the last start ended (for the script that asked)
  bool scriptStarting_ = false;

  std::vector<lessons::Course> courses_;
  int courseIndex_ = 0;
  std::vector<LessonRow> rows_;
  std::vector<lessons::StructureProgress> due_;
  bool modeQuizOnly_ = false;

  std::optional<lessons::StepView> step_;  // the engine's current step (nullopt: no lesson running)
  std::optional<Asked> asked_;
  std::optional<double> finishedScore_;    // the lesson just finished
  std::string runningLesson_;
  std::string message_;
  char userEdit_[64] = "";
};

}  // namespace at::app
