// Practical exams (ARCHITECTURE.md §5): an instructor defines an exam in the course (ExamSpec:
// structures, item kinds, count, time limit); a student takes it with labels hidden and no
// feedback until the end, against a clock.
//
//   start(user, exam) ──► items drawn (stored at once) ──answer(i)── … ──► finish() ──► results
//        │ resumes the open attempt; one past its deadline is finished with what was answered
//
// Items: `count` of the exam's structure × kind pairs, every structure once before any twice, in
// an order fixed by the exam, the user and the attempt number. Locate items select the target's
// nearest neighbour by weighted distance (its context shows the region, the target is not marked)
// and alternate over the exam's locate views (3-D, slice); identify items offer the target and its
// three nearest structures; name items ask for the name of the marked target.
//
// Every answer is graded when given and recorded at once (item, FSRS memory state, review log,
// Elo: one transaction), but answer() returns no grade: the student sees the results only from
// finish(). After the deadline answers are refused and nothing is recorded.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lessons/curriculum.h"
#include "lessons/lesson_engine.h"
#include "lessons/repositories.h"
#include "quiz/grading.h"
#include "quiz/keys.h"

namespace at::lessons {

struct ExamItem {
  std::int64_t id = 0;          // set by the repository
  int position = 0;             // 0-based order in the attempt
  quiz::ResolvedQuestion question;  // generated, keys resolved (id "<exam id>.<kind>.<structure>")
  ExamLocateView locateView = ExamLocateView::ThreeD;  // locate items: where the pick is made
  // What the view shows. Locate: the target's neighbour; the side it is seen from is a default that
  // the app replaces by one from which the target can be seen (clicked).
  QuestionScene scene;
  // The answer, once given:
  std::optional<quiz::Answer> answer;
  bool correct = false;
  double score = 0;
  std::int64_t latencyMs = 0;
  UnixSeconds answeredAt = 0;
};

struct ExamAttempt {
  std::int64_t id = 0;
  std::int64_t userId = 0;
  std::string examId;
  std::string courseId;
  UnixSeconds startedAt = 0;
  UnixSeconds deadline = 0;                // startedAt + the time limit
  std::optional<UnixSeconds> finishedAt;
  double score = 0;                        // mean item score (unanswered = 0), set when finished
  std::optional<bool> passed;              // when the exam has a pass score
};

// One exam answer and what it changes (written in ONE transaction).
struct ExamAnswerRecord {
  std::int64_t attemptId = 0;
  int position = 0;
  GradedAnswer answer;
  LearnerUpdate update;
};

// Storage of exam attempts (db/ implements it on SQLite).
class ExamRepository {
 public:
  virtual ~ExamRepository() = default;
  // The user's unfinished attempt at the exam (the latest), if any.
  virtual Result<std::optional<ExamAttempt>> openExamAttempt(std::int64_t userId, const std::string& examId) = 0;
  // A new attempt with its items (ids set), in one transaction.
  virtual Result<ExamAttempt> startExamAttempt(const ExamAttempt& attempt, std::vector<ExamItem>& items) = 0;
  virtual Result<std::vector<ExamItem>> examItems(std::int64_t attemptId) = 0;
  // The item's answer, grade, the structure's memory state, a review-log entry (source exam), the
  // ability and the question difficulty, COMMITTED before returning. Error if already answered.
  virtual Status recordExamAnswer(const ExamAnswerRecord& record) = 0;
  virtual Status finishExamAttempt(std::int64_t attemptId, UnixSeconds finishedAt, double score,
                                   std::optional<bool> passed) = 0;
  // The user's attempts at every exam, newest first.
  virtual Result<std::vector<ExamAttempt>> examAttempts(std::int64_t userId) = 0;
};

// What the student sees of an item: no structure name unless the prompt asks to locate it, no grade.
struct ExamItemView {
  int position = 0;        // 0-based
  int count = 0;           // items in the attempt
  quiz::QuestionKind kind = quiz::QuestionKind::Locate;
  std::string prompt;
  std::vector<std::string> choiceIds;    // identify
  std::vector<std::string> choiceNames;
  ExamLocateView locateView = ExamLocateView::ThreeD;
  QuestionScene scene;
  std::string target;      // for the renderer only (the view's framing); never shown
  bool answered = false;
};

struct ExamItemResult {
  int position = 0;
  std::string structure;
  quiz::QuestionKind kind = quiz::QuestionKind::Locate;
  bool answered = false;
  bool correct = false;
  double score = 0;
  std::string feedback;  // the grading feedback, or "Not answered."
  // For the review after the exam: the item's prompt, the student's answer and the key in words
  // (lessons::answerText / rightAnswerText; yourAnswer empty when not answered), and the scene that
  // shows the answer (showMeScene of the item's scene: the target in its own WDT view).
  std::string prompt;
  std::string yourAnswer;
  std::string rightAnswer;
  QuestionScene scene;
};

struct ExamResult {
  double score = 0;
  std::optional<bool> passed;
  int answered = 0;
  int correct = 0;
  bool timeRanOut = false;  // finished at or after the deadline
  std::vector<ExamItemResult> items;
};

// The exam with this id among the curriculum's courses, and its course.
Result<std::pair<Course, ExamSpec>> findExam(CurriculumRepository& curriculum, const std::string& examId);

// The items of one attempt, drawn as the header describes; `seed` fixes the order.
//
// Locate items are chosen like lesson views, so that every one can be answered: given the exam's
// `course`, a locate item on a structure takes the scene (region structure, preset, side, camera,
// clip) and the tolerance of the first lesson question of the course that asks to locate that
// structure — views the course checks are answerable (a click on the target's centre picks it:
// tests/app/test_question_scenes.cpp, `course validate`). A structure that no lesson asks to locate
// is asked only in the exam's other kinds: each structure's kinds are the ones it can be asked in,
// in a shuffled order, so its kind is drawn evenly among them and no item comes twice (an exam
// whose count exceeds the items its structures can be asked in is an error). Only when
// locate is the exam's one kind, or without a course, does its region fall back to the target's
// nearest neighbour by WDT distance with no tolerance (the app then turns the view to a side from
// which the target can be clicked).
Result<std::vector<ExamItem>> drawExamItems(const ExamSpec& exam, const std::vector<Structure>& structures,
                                            quiz::KeyComputer& keys, const std::string& seed,
                                            const Course* course = nullptr);

// How many different items `exam` can ask (its pool): each structure once per kind it can be asked
// in — locate only where a lesson of `course` locates it, unless locate is the exam's one kind or
// there is no course. drawExamItems refuses an exam whose count exceeds it.
std::size_t examPoolSize(const ExamSpec& exam, const Course* course = nullptr);

// The first lesson question of `course` that asks to locate `structureId`, or nullptr.
const Step* lessonLocateStep(const Course& course, const std::string& structureId);

class ExamSession {
 public:
  ExamSession(CurriculumRepository& curriculum, ProgressRepository& progress, ExamRepository& exams,
              quiz::KeyComputer& keys, EngineOptions options = {});

  // Starts the user's attempt or resumes the open one. Errors: unknown exam, unfinished
  // prerequisites (naming them), a structure that is not in the course's dataset.
  Status start(std::int64_t userId, const std::string& examId);
  bool resumed() const { return resumed_; }
  const ExamAttempt& attempt() const;
  const ExamSpec& exam() const { return exam_; }
  int itemCount() const { return int(items_.size()); }

  UnixSeconds secondsLeft() const;  // 0 once the time is up
  bool finished() const;
  // The first unanswered item, nullopt when every item is answered.
  std::optional<int> nextUnanswered() const;
  Result<ExamItemView> item(int position) const;
  // The generated question of an item (keys included; for the app's picking).
  Result<quiz::ResolvedQuestion> itemQuestion(int position) const;

  // Grades and records the answer; returns nothing about it. Errors: time is up, already
  // answered, an answer that does not fit the item, a storage failure (nothing recorded).
  Status answer(int position, const quiz::Answer& answer, std::int64_t latencyMs,
                const RenderState& render = {});

  // Finishes the attempt (unanswered items score 0) and returns every item's result.
  Result<ExamResult> finish();

 private:
  UnixSeconds now() const;
  Result<ExamResult> results() const;

  CurriculumRepository& curriculum_;
  ProgressRepository& progress_;
  ExamRepository& exams_;
  quiz::KeyComputer& keys_;
  EngineOptions options_;

  Course course_;
  ExamSpec exam_;
  std::optional<ExamAttempt> attempt_;
  std::vector<ExamItem> items_;
  quiz::GradingContext context_;
  bool resumed_ = false;
};

}  // namespace at::lessons
