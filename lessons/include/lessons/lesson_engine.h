// The lesson state machine (ARCHITECTURE.md §5):
//
//   start(user, lesson) ──► [step shown] ──answer()──► [feedback] ──next()──► [step shown] … ──► finish()
//          │ resumes an open attempt at its first unanswered step
//
// Show steps need only next(). Every answer is graded, rated (lessons/scheduling.h) and recorded
// through ProgressRepository::recordAnswer (response + FSRS memory state + review log + Elo, one
// committed transaction) BEFORE answer() returns its feedback. A lesson whose prerequisites are not finished cannot start.
// QuizOnly mode skips show steps and hides labels and structure names in step views.
//
// Review questions (chooseReviewQuestion) are asked outside any attempt; answerReview grades them
// the same way and records them through ProgressRepository::recordReviewAnswer, so the review
// queue moves after a review exactly as after a lesson answer.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "lessons/repositories.h"
#include "lessons/scheduling.h"
#include "quiz/elo.h"
#include "quiz/grading.h"
#include "quiz/keys.h"

namespace at::lessons {

struct EngineOptions {
  double eloK = quiz::kDefaultEloK;
  FsrsParameters fsrs;  // must pass validate()
  std::function<UnixSeconds()> clock;  // empty = the system clock
};

// The lessons of `lessonIds` the user has not finished, as "'id' (title), …" ("" when none).
Result<std::string> unfinishedLessons(CurriculumRepository& curriculum, ProgressRepository& progress,
                                      std::int64_t userId, const std::vector<std::string>& lessonIds);

// The scene of the course's question `questionId` (sceneFor its step); nullopt if not in the course.
std::optional<QuestionScene> questionScene(const Course& course, const std::string& questionId);

// The options' clock, else the system clock.
UnixSeconds clockNow(const EngineOptions& options);

// What one graded answer to `question` at `at` does to the learner model (read from `progress`):
// its FSRS rating, the target structure's next memory state, the Elo update. Nothing is written.
Result<LearnerUpdate> learnerUpdate(ProgressRepository& progress, std::int64_t userId, const quiz::Question& question,
                                    const quiz::Grade& grade, std::int64_t latencyMs, UnixSeconds at,
                                    const EngineOptions& options);

// What the UI (or `play`) shows for the current step.
struct StepView {
  int index = 0;            // in the lesson's steps
  int position = 0;         // 1-based among the steps this mode shows
  int count = 0;            // steps this mode shows
  StepKind kind = StepKind::Show;
  bool labelsVisible = true;  // false in QuizOnly: no labels, no structure names
  // Show
  std::string structure;      // id (always: the renderer needs it)
  std::string structureName;  // display name; empty when labels are hidden
  std::string presetId;
  CameraView view = CameraView::LateralRight;
  std::string title;
  std::string text;
  // Question
  std::string questionId;
  quiz::QuestionKind questionKind = quiz::QuestionKind::Locate;
  std::string prompt;
  std::vector<std::string> choiceIds;    // Identify/Relation/Order
  std::vector<std::string> choiceNames;  // display names of choiceIds
  std::optional<quiz::Grade> feedback;   // set once answered
  // What the 3-D view shows (both kinds): a show step's structure, preset and view; a question's
  // scene (sceneFor).
  QuestionScene scene;
};

// One question of a lesson or exam as the review after it shows it.
struct QuestionOutcome {
  int position = 0;                  // 1-based among the steps shown
  std::string questionId;
  quiz::QuestionKind kind = quiz::QuestionKind::Locate;
  std::string prompt;
  std::string target;                // structure id the question is about
  std::string yourAnswer;            // in words: the choice's or clicked structure's name, the typed text
  std::string rightAnswer;           // in words: the key
  std::optional<quiz::Grade> grade;  // nullopt = not answered
  QuestionScene scene;               // showMeScene of the question
};

// "Show me": the scene that shows a question's answer — its target highlighted in its own WDT
// context (preset "<target>_wdt"), seen from the side the question was asked from, with the
// question's camera and clip. For relation and order questions the target is the structure the
// question trains (Question::target).
QuestionScene showMeScene(const Step& questionStep);
// The same for a question asked in `asked` (an exam item's or a review question's scene) about
// `target`: the scene, its structure and preset replaced by the target's when they differ.
QuestionScene showMeScene(QuestionScene asked, const std::string& target);

// The key of a resolved question and an answer to it, in words (display names of `context`).
std::string rightAnswerText(const quiz::ResolvedQuestion& question, const quiz::GradingContext& context);
std::string answerText(const quiz::ResolvedQuestion& question, const quiz::Answer& answer,
                       const quiz::GradingContext& context);

// The names a typed answer may use for each structure of a course's dataset: its display name,
// its id with spaces for underscores, the dataset's structure catalogue (name, synonyms, Latin
// names, side: lessons/structure_catalogue.h) and the course's synonyms. Without a catalogue entry
// the side is read off the display name. Lesson, review and exam answers are graded with this.
quiz::GradingContext gradingContext(const std::vector<Structure>& structures, const Course& course);

class LessonEngine {
 public:
  LessonEngine(CurriculumRepository& curriculum, ProgressRepository& progress, quiz::KeyComputer& keys,
               EngineOptions options = {});

  // Starts the user's attempt at the lesson, or resumes the open one (then its stored mode wins
  // and `mode` is ignored). Errors: unknown lesson, unfinished prerequisites (naming them), a
  // study step, a question whose key cannot be computed.
  Status start(std::int64_t userId, const std::string& lessonId, LessonMode mode = LessonMode::Guided);

  bool started() const { return attempt_.has_value(); }
  bool resumed() const { return resumed_; }
  const Attempt& attempt() const;
  const Lesson& lesson() const { return lesson_; }
  // True when every shown step has been passed (next() past the last one).
  bool atEnd() const;

  // The current step; error when not started or at the end.
  Result<StepView> current() const;
  // The resolved question of the current step (keys included; for the app's pick sampling).
  Result<quiz::ResolvedQuestion> currentQuestion() const;

  // The indices (in lesson().steps) of up to `count` steps this mode shows after the current one,
  // in order: what a view can prepare while the student reads.
  std::vector<int> upcomingSteps(int count) const;

  // Grades and records the answer to the current question step. Errors: not a question step,
  // already answered, an answer that does not fit (reported, nothing recorded), storage failure
  // (nothing graded counts as given).
  Result<quiz::Grade> answer(const quiz::Answer& answer, const RenderState& render, std::int64_t latencyMs);

  // Moves past the current step. Error on an unanswered question step or at the end.
  Status next();
  // Moves back to the previous step shown (from the end too: to the last one). An answered
  // question shows again with its feedback; answers are never changed. Error at the first step.
  Status back();

  // Every question step of the lesson shown so far or answered, in order: what was asked, the
  // student's answer, the right one, the grade and the scene to show it in (the end-of-lesson
  // review). Unanswered questions have no grade and an empty `yourAnswer`.
  std::vector<QuestionOutcome> outcomes() const;

  // Finishes the attempt (all question steps answered), storing the mean score; returns it.
  Result<double> finish();

  // Current Elo ability of the user (kDefaultAbility before any answer).
  Result<double> ability() const;

 private:
  UnixSeconds now() const;

  CurriculumRepository& curriculum_;
  ProgressRepository& progress_;
  quiz::KeyComputer& keys_;
  EngineOptions options_;

  Lesson lesson_;
  Course course_;
  std::vector<Structure> structures_;
  std::optional<Attempt> attempt_;
  bool resumed_ = false;
  std::vector<int> shown_;                                 // step indices this mode shows
  std::vector<std::optional<quiz::ResolvedQuestion>> resolved_;  // per step
  std::vector<std::optional<quiz::Grade>> grades_;         // per step
  std::vector<std::optional<quiz::Answer>> answers_;       // per step, as given (or as stored)
  std::size_t cursor_ = 0;                                 // into shown_
};

// Review (ARCHITECTURE.md §5) asks only about what the user has been taught. A structure is
// TAUGHT in a course when the user has started (any attempt) a lesson of that course with a
// question on it, and has answered about it at least once (it has an FSRS memory state). These
// functions are the one definition of what is due: `progress`, `play --review` and the desktop
// panels all count and ask through them.

// The rule itself, on plain records: the ids (sorted) of the course's structures that are targets of
// questions in lessons the user has started and of which the user has a memory state.
std::vector<std::string> taughtStructureIds(const Course& course, const std::vector<Attempt>& userAttempts,
                                            const std::vector<StructureProgress>& userMemories);

// The course's structures taught to the user, with their progress, ordered by id.
Result<std::vector<StructureProgress>> taughtStructures(CurriculumRepository& curriculum, ProgressRepository& progress,
                                                        std::int64_t userId, const std::string& courseId);

// The taught structures due for review at `now` (memory.due <= now), earliest due first.
Result<std::vector<StructureProgress>> reviewQueue(CurriculumRepository& curriculum, ProgressRepository& progress,
                                                   std::int64_t userId, const std::string& courseId, UnixSeconds now);

// Adaptive review: among the questions of the lessons the user has started in the course whose
// structure is due at `now` (reviewQueue), the one whose difficulty best matches the user's ability
// (quiz::chooseAdaptive). nullopt when nothing is due.
Result<std::optional<quiz::Question>> chooseReviewQuestion(CurriculumRepository& curriculum,
                                                           ProgressRepository& progress, std::int64_t userId,
                                                           const std::string& courseId, UnixSeconds now);

// An answer to a review question.
struct ReviewAnswer {
  std::int64_t userId = 0;
  std::string courseId;        // the course the question was chosen from
  quiz::Question question;     // as chooseReviewQuestion gave it (only its id is used: the
                               // course's stored question is graded)
  quiz::Answer answer;
  RenderState render;          // on screen when it was given
  std::int64_t latencyMs = 0;  // from the question being shown to the answer
};

// Grades a review answer as LessonEngine::answer grades a lesson answer (the question's keys
// resolved through `keys`, the course's gradingContext), reschedules the structure (FSRS,
// scheduleAnswer), updates the Elo ability and question difficulty, and records all of it through
// ProgressRepository::recordReviewAnswer (one committed transaction) before returning the grade.
// Errors: unknown course, a question not in the course, keys that cannot be computed, an answer
// that does not fit the question, a storage failure — in every case nothing is recorded.
Result<quiz::Grade> answerReview(CurriculumRepository& curriculum, ProgressRepository& progress,
                                 quiz::KeyComputer& keys, const ReviewAnswer& review,
                                 const EngineOptions& options = {});

}  // namespace at::lessons
