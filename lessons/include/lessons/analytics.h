// Instructor analytics for one course and one class (ARCHITECTURE.md §5): pure computations over
// plain records that db/ loads (db/analytics_store.h); `anatomy-tutor analytics` prints them.
//
//   question difficulty   Elo with an uncertainty factor, replayed over every answer of the class
//                         in time order: E = 1/(1 + 10^((d − θ)/400)),
//                         θ ← θ + K·U(n_student)·(s − E),  d ← d − K·U(n_question)·(s − E),
//                         U(n) = 1/(1 + 0.05·n) with n the answers counted so far, K = 400/ln 10
//                         (one logit: the natural-logistic form with α = 1); θ starts at 1500, d at
//                         the question's initial difficulty from the course.
//   hardest structures    share of right answers (lowest first), then the class's mean FSRS
//                         difficulty; with the mean predicted recall now.
//   completion per lesson students with a finished attempt / students in the class; the mean of
//                         each finisher's best score over the ends whose score is known (a class
//                         server's end waiting for its keys counts as finished, not as a score).
//   predicted recall      per student: the mean FSRS retrievability now over the structures taught
//                         (lessons::taughtStructures' rule), the weakest one, and how many are due.
//   exams                 attempts, mean score, pass rate; each student's latest finished score.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "lessons/curriculum.h"
#include "lessons/exam.h"
#include "lessons/fsrs.h"
#include "lessons/lesson_engine.h"
#include "lessons/repositories.h"

namespace at::lessons {

// One answer of a student to a question of the course (lesson, review or exam).
struct ClassAnswer {
  std::int64_t userId = 0;
  std::string questionId;
  std::string structureId;
  AnswerSource source = AnswerSource::Lesson;
  double score = 0;
  bool correct = false;
  UnixSeconds answeredAt = 0;
  std::int64_t order = 0;  // tie-break among answers given in the same second (the row order)
  // As the review log keeps them, for exporting it to an FSRS optimiser:
  Rating rating = Rating::Good;
  std::int64_t latencyMs = 0;
  MemoryPhase phaseBefore = MemoryPhase::New;
};

struct AnalyticsInput {
  Course course;
  std::vector<Structure> structures;          // of the course's dataset (display names)
  std::vector<User> students;                 // the class
  std::vector<ClassAnswer> answers;           // any order
  std::vector<Attempt> attempts;              // lesson attempts of the class
  std::vector<StructureProgress> memories;    // memory states of the class
  std::vector<ExamAttempt> examAttempts;      // attempts at the course's exams by the class
  int waitingAnswers = 0;  // on a class server: answers not graded yet (no key published), not in `answers`
};

inline constexpr double kAnalyticsEloK = 173.71779276130073;  // 400 / ln 10
double uncertaintyFactor(int answersSoFar);                     // U(n) = 1 / (1 + 0.05 n)

struct QuestionStats {
  std::string questionId;
  std::string lessonId;    // or the exam id for exam items
  std::string structureId;
  std::string kind;
  int answers = 0;
  int correct = 0;
  double correctShare = 0;
  double initialDifficulty = 1500;
  double difficulty = 1500;  // Elo with uncertainty after the replay
};

struct StructureStats {
  std::string structureId;
  std::string name;
  int answers = 0;
  int correct = 0;
  double correctShare = 0;
  int students = 0;              // students with a memory state of it
  double meanDifficulty = 0;     // FSRS difficulty 1..10, mean over those students
  double meanRecall = 0;         // predicted recall now, mean over those students
};

struct LessonCompletion {
  std::string lessonId;
  std::string title;
  int started = 0;
  int finished = 0;
  double completion = 0;         // finished / class size
  std::optional<double> meanBestScore;  // over students who finished with a known score
  int scoresUnknown = 0;                // students who finished, none of whose ends has a known score yet
};

struct StudentRecall {
  std::int64_t userId = 0;
  std::string name;
  std::string group;
  int taught = 0;
  int due = 0;
  std::optional<double> meanRecall;     // nullopt when nothing is taught
  std::string weakestStructure;
  double weakestRecall = 0;
  int lessonsFinished = 0;
  std::optional<double> examScore;      // latest finished exam attempt
};

struct ExamStats {
  std::string examId;
  std::string title;
  int attempts = 0;
  int finished = 0;
  std::optional<double> meanScore;      // over finished attempts
  std::optional<double> passRate;       // when the exam has a pass score
};

struct ClassAnalytics {
  std::string courseId;
  int classSize = 0;
  int answers = 0;
  std::vector<QuestionStats> questions;      // hardest (highest difficulty) first
  std::vector<StructureStats> structures;    // hardest first (answered ones only)
  std::vector<LessonCompletion> lessons;     // in teaching order
  std::vector<StudentRecall> students;       // lowest mean recall first
  std::vector<ExamStats> exams;
};

ClassAnalytics computeAnalytics(const AnalyticsInput& input, UnixSeconds now, const Fsrs& fsrs = Fsrs());

// The items the class missed most: questions (and exam items) with at least one answer that was
// not right, by the number of such answers (most first), then by their share of the question's
// answers, then by id; at most `limit`.
std::vector<QuestionStats> mostMissed(const ClassAnalytics& analytics, std::size_t limit);

}  // namespace at::lessons
