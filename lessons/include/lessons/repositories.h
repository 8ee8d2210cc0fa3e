// Storage as seen by lessons/: small pure interfaces over plain structs. db/ implements them on
// SQLite; tests use an in-memory implementation. Every method reports failures as values.
// Times are Unix seconds (UTC).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lessons/curriculum.h"
#include "lessons/fsrs.h"
#include "quiz/question.h"
#include "core/error.h"
#include "volume/structure.h"

namespace at::lessons {

// ---------------------------------------------------------------------------------------------
// Curriculum (read side; seeding is db/'s business)
class CurriculumRepository {
 public:
  virtual ~CurriculumRepository() = default;
  // Every course with its lessons, steps and questions.
  virtual Result<std::vector<Course>> courses() = 0;
  // Error "unknown course 'x'" if absent.
  virtual Result<Course> course(const std::string& courseId) = 0;
  // Error "unknown lesson 'x'" if absent.
  virtual Result<Lesson> lesson(const std::string& lessonId) = 0;
  // Error "unknown question 'x'" if absent.
  virtual Result<quiz::Question> question(const std::string& questionId) = 0;
  // The structures of a dataset (ids and display names); error if the dataset is unknown.
  virtual Result<std::vector<Structure>> structures(const std::string& datasetId) = 0;
  // A stored course or lesson that cannot be read back (a damaged row: broken JSON, an unknown
  // kind) is left out of courses() and course() instead of failing them, so that every other
  // course and lesson still works. This returns one line per row left out since the last call,
  // naming the row and the problem (each row once per repository).
  virtual std::vector<std::string> takeSkipped() { return {}; }
};

// ---------------------------------------------------------------------------------------------
// Users (pseudonymous: a chosen name, never a real identity)
enum class Role { Student, Expert, Coordinator };
const char* toString(Role role);  // "student", "expert", "coordinator"
Result<Role> parseRole(const std::string& text);

struct User {
  std::int64_t id = 0;
  std::string name;         // pseudonym, unique
  Role role = Role::Student;
  std::string group;        // e.g. "first-year 2026", may be empty
};

class UserRepository {
 public:
  virtual ~UserRepository() = default;
  virtual Result<std::optional<User>> findUser(const std::string& name) = 0;
  virtual Result<User> user(std::int64_t userId) = 0;  // error if unknown
  // Error if the name is taken or empty. Returns the user with its id.
  virtual Result<User> createUser(const std::string& name, Role role, const std::string& group) = 0;
  virtual Result<std::vector<User>> users() = 0;
};

// ---------------------------------------------------------------------------------------------
// Attempts, responses, progress, adaptation
enum class LessonMode {
  Guided,    // show steps and questions
  QuizOnly,  // questions only; labels and structure names hidden in step views
};
const char* toString(LessonMode mode);  // "guided", "quiz_only"
Result<LessonMode> parseLessonMode(const std::string& text);

struct Attempt {
  std::int64_t id = 0;
  std::int64_t userId = 0;
  std::string lessonId;
  LessonMode mode = LessonMode::Guided;
  UnixSeconds startedAt = 0;
  std::optional<UnixSeconds> finishedAt;  // unset while in progress
  double score = 0;                        // mean question score, set when finished
  // False for an end whose score is not known yet: on a class server, one of its answers waits
  // for its key (or every answer was practice); `score` is then 0 and means nothing.
  bool scoreKnown = true;
};

// Render parameters on screen when the answer was given.
struct RenderState {
  std::string presetId;
  std::string mode;  // "wdt", "bare", …
  double t = 0.5;
  double alpha = 1.6;
  double beta = 1.0;
};

// One graded answer, as a lesson step and a review question both record it.
struct GradedAnswer {
  std::string questionId;
  std::string structureId;    // the question's target
  quiz::Answer answer;        // stored verbatim (quiz/answer_json.h gives a JSON form)
  bool correct = false;
  double score = 0;
  std::int64_t latencyMs = 0; // from the question being shown to the answer
  RenderState render;
  UnixSeconds answeredAt = 0;
};

// An answer to a lesson step.
struct Response : GradedAnswer {
  std::int64_t id = 0;        // set by the repository
  std::int64_t attemptId = 0;
  int stepIndex = 0;          // index in the lesson's steps
};

// What one user remembers of one structure (FSRS memory state: phase, stability, difficulty,
// next review) and how often they answered about it.
struct StructureProgress {
  std::int64_t userId = 0;
  std::string structureId;
  MemoryState memory;         // memory.phase == New: never answered
  int answered = 0;
  int correct = 0;
};

// What one graded answer changes in the learner model, written with the answer in ONE transaction:
// the structure's memory state (and a review-log entry from before → after), the user's Elo
// ability and the question's Elo difficulty.
struct LearnerUpdate {
  StructureProgress progress;     // the structure's state after this answer
  MemoryState memoryBefore;       // its memory state before (the review log keeps both)
  Rating rating = Rating::Good;   // the FSRS rating the answer was given (ratingFor)
  double abilityAfter = 1500;     // the user's Elo ability after this answer
  double difficultyAfter = 1500;  // the question's Elo difficulty after this answer
};

// Everything one lesson answer changes.
struct AnswerRecord {
  Response response;
  LearnerUpdate update;
};

// One answer to a review question (asked outside any lesson attempt, lessons::answerReview).
struct ReviewResponse : GradedAnswer {
  std::int64_t id = 0;        // set by the repository
  std::int64_t userId = 0;
};

// Everything one review answer changes.
struct ReviewRecord {
  ReviewResponse response;
  LearnerUpdate update;
};

// Where a logged answer was given.
enum class AnswerSource { Lesson, Review, Exam };
const char* toString(AnswerSource source);  // "lesson", "review", "exam"
Result<AnswerSource> parseAnswerSource(const std::string& text);

// One row of the review log: every graded answer, with the FSRS rating it gave and the memory
// state it produced, kept so that FSRS parameters can be optimised on the class's own history.
// Rows rebuilt from answers given before FSRS (`rebuilt`) carry the rating only: phaseBefore is
// New, elapsedDays −1 and `after` empty.
struct ReviewLogEntry {
  std::int64_t id = 0;
  std::int64_t userId = 0;
  std::string structureId;
  std::string questionId;
  AnswerSource source = AnswerSource::Lesson;
  UnixSeconds reviewedAt = 0;
  Rating rating = Rating::Good;
  bool correct = false;
  double score = 0;
  std::int64_t latencyMs = 0;
  MemoryPhase phaseBefore = MemoryPhase::New;
  int elapsedDays = -1;        // whole days since the previous answer; −1 for the first
  MemoryState after;
  bool rebuilt = false;
};

class ProgressRepository {
 public:
  virtual ~ProgressRepository() = default;
  // The user's unfinished attempt at the lesson (the latest if several), if any.
  virtual Result<std::optional<Attempt>> openAttempt(std::int64_t userId, const std::string& lessonId) = 0;
  // A new attempt (id set). The engine only calls it when openAttempt gave none.
  virtual Result<Attempt> startAttempt(std::int64_t userId, const std::string& lessonId, LessonMode mode,
                                       UnixSeconds startedAt) = 0;
  virtual Status finishAttempt(std::int64_t attemptId, UnixSeconds finishedAt, double score) = 0;
  // The user's attempts at every lesson, newest first.
  virtual Result<std::vector<Attempt>> attempts(std::int64_t userId) = 0;
  // True if the user has at least one finished attempt at the lesson.
  virtual Result<bool> hasFinished(std::int64_t userId, const std::string& lessonId) = 0;
  // Responses of an attempt in the order they were recorded.
  virtual Result<std::vector<Response>> responses(std::int64_t attemptId) = 0;
  // Stores the response, the structure's progress, a review-log entry, the ability and the question
  // difficulty in one transaction, COMMITTED (durable) before returning. Returns the response id.
  virtual Result<std::int64_t> recordAnswer(const AnswerRecord& record) = 0;
  // As recordAnswer, for an answer to a review question: the review response, the structure's
  // progress, a review-log entry, the ability and the question difficulty in one transaction, COMMITTED before
  // returning; on failure nothing is stored. Returns the review response id.
  virtual Result<std::int64_t> recordReviewAnswer(const ReviewRecord& record) = 0;
  // The user's review responses in the order they were recorded.
  virtual Result<std::vector<ReviewResponse>> reviewResponses(std::int64_t userId) = 0;
  // The user's review log (lesson, review and exam answers alike), oldest first.
  virtual Result<std::vector<ReviewLogEntry>> reviewLog(std::int64_t userId) = 0;
  // nullopt = never answered.
  virtual Result<std::optional<StructureProgress>> progress(std::int64_t userId, const std::string& structureId) = 0;
  virtual Result<std::vector<StructureProgress>> allProgress(std::int64_t userId) = 0;
  // nullopt = no answer yet (the engine then uses quiz::kDefaultAbility).
  virtual Result<std::optional<double>> ability(std::int64_t userId) = 0;
  // nullopt = never answered by anyone (the engine then uses the question's initial difficulty).
  virtual Result<std::optional<double>> questionDifficulty(const std::string& questionId) = 0;
};

}  // namespace at::lessons
