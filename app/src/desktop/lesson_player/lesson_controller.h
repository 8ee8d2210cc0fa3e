// The desktop's lessons without drawing (the Lessons panel draws it; the UI script drives the same
// commands): course and lesson lists with the user's progress and prerequisites, a lesson's steps
// through lessons::LessonEngine (prerequisites enforced; every answer graded and committed to the
// database before its feedback shows), every question kind (locate: a click in the 3-D view,
// handed over by the model), the lesson's score at the end, and review (the structures due, and an
// adaptive review question answered through lessons::answerReview, so the review queue moves).
//
// It works through the app's learning session (the same database, repositories, users and answer
// keys as `anatomy-tutor play`, so desktop and terminal progress are one). It never touches the
// view: what a step shows goes out through `ShowStructure`; while a question must not give its
// answer away (identify/name/locate questions, quiz-only lessons) namesHidden() is true.
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

#include "core/error.h"
#include "learning_session.h"
#include "lessons/curriculum.h"
#include "lessons/lesson_engine.h"
#include "lessons/review_session.h"
#include "quiz/question.h"

namespace at::app {

// Questions whose answer a visible structure name would give away while unanswered (locate,
// identify, name): a lesson hides names while one is asked, the course editor's preview too.
bool namesGiveAway(quiz::QuestionKind kind);

class LessonController {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  // What the view should show for a step: the structure (id) with a preset (id; empty = the
  // structure's WDT preset) from a named view (nullopt = keep the current camera direction).
  struct Shown {
    std::string structure;
    std::string presetId;
    std::optional<lessons::CameraView> view;
    std::optional<lessons::StepCamera> camera;  // replaces the view's framing
    std::optional<lessons::StepClip> clip;      // none: unclipped
    std::string alsoInView;  // a locate question's target: framed with the structure, not marked
    // "Show me on a slice": besides the 3-D view, the axial CT slice through the structure's
    // anchor with the structure alone overlaid, shown in place of the 3-D view until the next step.
    bool onSlice = false;
  };
  using ShowStructure = std::function<void(const Shown&)>;
  // The render parameters on screen, stored with each answer.
  using RenderStateSource = std::function<lessons::RenderState()>;

  // `session` outlives the controller. `userName`: the pseudonymous user, created as a student
  // when they first record something (a lesson, a review answer, an exam), never by looking: an
  // instructor who opens the desktop to read the class's analytics is not made a student of it.
  // `viewDataset`: the id of the dataset the view shows.
  LessonController(LearningSession& session, std::string userName, std::string viewDataset, EventSink events,
                   ShowStructure show, RenderStateSource renderState);
  ~LessonController();

  // --- State, for the panel -------------------------------------------------------------------
  // Opens the user and the lists on first use; an error is kept (not retried every frame). A user
  // not in the database yet is shown with id 0 (no records) and stored by storedUserId.
  Status ready();
  const lessons::User* user() const { return user_ ? &*user_ : nullptr; }
  // The user's id, creating their row (a student) if they have none yet: for what records.
  Result<std::int64_t> storedUserId();
  const std::string& viewDataset() const { return viewDataset_; }
  void setViewDataset(std::string id) { viewDataset_ = std::move(id); }
  const std::vector<lessons::Course>& courses() const { return courses_; }
  int courseIndex() const { return courseIndex_; }
  struct LessonRow {
    std::string id, title, summary;
    std::vector<std::string> missing;  // unfinished prerequisites (titles): locked when not empty
    int attempts = 0;
    bool open = false;                 // an unfinished attempt exists
    std::optional<double> bestScore;   // of finished attempts
    int questions = 0;
  };
  const std::vector<LessonRow>& rows() const { return rows_; }
  const std::vector<lessons::StructureProgress>& due() const { return due_; }
  bool quizOnly = false;               // mode of the next lesson started from the list
  // A lesson being prepared (its answer keys computed on a thread): its title.
  std::optional<std::string> preparing() const;
  const std::optional<lessons::StepView>& step() const { return step_; }
  const lessons::LessonEngine* engine() const { return engine_.get(); }
  std::optional<double> finishedScore() const { return finishedScore_; }
  // A question being asked: the current lesson step's, or a review question. The panel edits the
  // answer being composed (choice, text, order) in place.
  struct Asked {
    quiz::ResolvedQuestion question;
    std::vector<std::string> choiceNames;
    bool review = false;
    std::optional<quiz::Grade> grade;
    std::vector<std::string> order;     // Order: the student's sequence so far (ids)
    int choice = -1;                    // Identify/Relation: the selected choice
    std::string text;                   // Name: typed so far
    // Answered with a locate pick the class server the answers go to keeps as practice (a click
    // in the free 3-D view carries no pixel of a fixed picture): the panel says so (class_practice.h).
    bool keptAsPractice = false;
    std::chrono::steady_clock::time_point shownAt = std::chrono::steady_clock::now();
  };
  Asked* asked() { return asked_ ? &*asked_ : nullptr; }
  const std::string& message() const { return message_; }
  std::string displayName(const std::string& structureId) const;

  // The user's answers go to a class server (answersGoToClassServer, read at each refresh), which
  // keeps a locate click in the 3-D view as practice: the panel says so before and after one.
  bool answersGoToClass() const { return answersGoToClass_; }
  // The current step is a locate question not yet answered: a click in the view answers it.
  bool wantsClick() const;
  // ... accepting clicks near its target (a tolerance in mm): a click off the target needs its
  // weighted distance from the target to be graded.
  bool wantsClickDistance() const;
  // Structure names must not be shown anywhere while this is true.
  bool namesHidden() const;
  // The target of the current question, if any.
  std::optional<std::string> questionTarget() const;

  // --- Commands (the panel's widgets and the UI script) ---------------------------------------
  Status switchUser(const std::string& name);  // no lesson may be running [lesson_user]
  Status selectCourse(const std::string& courseId);
  Status selectCourse(int index);
  // The course to start on (the one the view opened for), applied when the courses are next read.
  void preferCourse(const std::string& courseId);
  Status refresh();                            // courses, lesson rows, review queue
  // Starts (or resumes) a lesson; its answer keys are computed on a thread and poll() (each frame)
  // completes the start [lesson_started, lesson_step; lesson_refused when it cannot start].
  Status startLesson(const std::string& lessonId, lessons::LessonMode mode);
  void poll();
  // How the last start ended, once (for a script waiting on it).
  std::optional<Status> takeStartResult();
  Status next();                               // past the current step [lesson_step | lesson_finished]
  // The previous step of the running lesson; an answered question shows with its feedback and
  // cannot be answered again [lesson_step]. (lesson_controller_review.cpp)
  Status back();
  // "Show me", once the question asked is answered: its target highlighted in its own WDT view
  // from the question's side (lessons::showMeScene), the explanation staying in the feedback
  // [show_me]. Back at the question with back()/next(). `onSlice`: the target highlighted on a
  // slice through its anchor as well (Shown::onSlice).
  Status showMe(bool onSlice = false);
  // The lesson just finished, question by question (lessons::LessonEngine::outcomes); empty
  // while a lesson runs. showReviewItem shows one of them in its show-me view [review_item].
  const std::vector<lessons::QuestionOutcome>& lessonReview() const { return review_; }
  Status showReviewItem(int index, bool onSlice = false);
  void leave();                                // answers are saved: Resume continues the attempt
  void backToLessons();                        // after the score
  Result<quiz::Grade> answer(const quiz::Answer& answer);  // grades and records [graded]
  // A click in the 3-D view on `structure` ("" for none) with its weighted distance from the
  // question's target (negative: unknown). True when it answered a locate question.
  bool clicked(const std::string& structure, double distanceMm = -1);
  Status startReview();                        // [review_question]
  void dismissReview();
  // Shows an error in the panel (and on stderr).
  void report(const std::string& text);

 private:
  Status showCurrent();
  Status finishLesson();
  Status completeStart();
  Result<quiz::KeyComputer*> keysFor(const std::string& datasetId);  // and the structures' names

  LearningSession& session_;
  std::string userName_;
  std::string viewDataset_;
  EventSink events_;
  ShowStructure show_;
  RenderStateSource renderState_;
  std::optional<lessons::User> user_;
  std::string readyError_;
  std::vector<Structure> structures_;         // of the course dataset last asked for
  std::unique_ptr<lessons::LessonEngine> engine_;
  std::unique_ptr<lessons::ReviewSession> reviewSession_;  // while a review question is asked
  // A lesson being started (declared after engine_: destroyed, that is joined, before it).
  struct Pending {
    std::unique_ptr<lessons::LessonEngine> engine;
    std::future<Status> started;
    std::string lessonId, courseId, title;
  };
  std::optional<Pending> pending_;
  std::optional<Status> startResult_;

  std::vector<lessons::Course> courses_;
  int courseIndex_ = 0;
  std::string preferredCourse_;  // preferCourse: chosen at the next refresh, then cleared
  std::vector<LessonRow> rows_;
  std::vector<lessons::StructureProgress> due_;
  std::optional<lessons::StepView> step_;     // the engine's current step (nullopt: no lesson running)
  std::optional<Asked> asked_;
  std::optional<double> finishedScore_;       // the lesson just finished
  std::vector<lessons::QuestionOutcome> review_;  // ... question by question
  std::string runningLesson_;
  std::string message_;
  bool answersGoToClass_ = false;
};

}  // namespace at::app
