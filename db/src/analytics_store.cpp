#include "db/analytics_store.h"

#include <algorithm>
#include <set>

#include "class_event_analytics.h"
#include "database.h"
#include "db/exam_store.h"

namespace at::db {

using namespace at::lessons;

Result<AnalyticsInput> loadAnalyticsInput(Database& db, CurriculumRepository& curriculum, const std::string& courseId,
                                          const std::optional<std::string>& group) {
  AnalyticsInput in;
  auto course = curriculum.course(courseId);
  if (!course) return tl::unexpected(course.error());
  in.course = std::move(*course);
  auto structures = curriculum.structures(in.course.datasetId);
  if (structures) in.structures = std::move(*structures);  // a dataset not here: ids are shown instead

  SqlUserRepository users(db);
  auto all = users.users();
  if (!all) return tl::unexpected(all.error());
  std::set<std::string> localNames;  // every user here, whatever their role
  for (const User& u : *all) localNames.insert(u.name);
  for (User& u : *all)
    if (u.role == Role::Student && (!group || u.group == *group)) in.students.push_back(std::move(u));

  std::set<std::string> questionIds;
  for (const Lesson& l : in.course.lessons)
    for (const Step& s : l.steps)
      if (s.kind == StepKind::Question) questionIds.insert(s.question.id);
  const auto ofCourse = [&](const std::string& questionId) {
    if (questionIds.count(questionId)) return true;
    for (const ExamSpec& e : in.course.exams)
      if (questionId.rfind(e.id + ".", 0) == 0) return true;
    return false;
  };

  SqlProgressRepository progress(db);
  SqlExamRepository exams(db);
  auto log = db.prepare(
      "SELECT id, user_id, question_id, structure, source, score, correct, reviewed_at, rating, latency_ms, phase_before"
      " FROM review_log"
      " WHERE user_id = ?1 ORDER BY reviewed_at, id");
  if (!log) return tl::unexpected(log.error());
  for (const User& u : in.students) {
    log->reset();
    log->bind(1, u.id);
    while (true) {
      auto row = log->step();
      if (!row) return tl::unexpected(row.error());
      if (!*row) break;
      ClassAnswer a;
      a.order = log->int64(0);
      a.userId = log->int64(1);
      a.questionId = log->text(2);
      if (!ofCourse(a.questionId)) continue;
      a.structureId = log->text(3);
      auto source = parseAnswerSource(log->text(4));
      if (!source) return fail("review log entry " + std::to_string(a.order) + ": " + source.error().message);
      a.source = *source;
      a.score = log->real(5);
      a.correct = log->integer(6) != 0;
      a.answeredAt = log->int64(7);
      a.rating = Rating(std::clamp(log->integer(8), 1, 4));
      a.latencyMs = log->int64(9);
      auto phase = parseMemoryPhase(log->text(10));
      if (!phase) return fail("review log entry " + std::to_string(a.order) + ": " + phase.error().message);
      a.phaseBefore = *phase;
      in.answers.push_back(std::move(a));
    }
    auto attempts = progress.attempts(u.id);
    if (!attempts) return tl::unexpected(attempts.error());
    in.attempts.insert(in.attempts.end(), attempts->begin(), attempts->end());
    auto memories = progress.allProgress(u.id);
    if (!memories) return tl::unexpected(memories.error());
    in.memories.insert(in.memories.end(), memories->begin(), memories->end());
  }
  // On a class server: the students whose work came through the outbox, from their class events.
  if (auto added = addClassEventStudents(db, in, localNames, questionIds, group); !added)
    return tl::unexpected(withContext("reading the class events", added.error()));
  auto examAttempts = exams.courseExamAttempts(courseId);
  if (!examAttempts) return tl::unexpected(examAttempts.error());
  in.examAttempts.insert(in.examAttempts.end(), examAttempts->begin(), examAttempts->end());  // after the server's
  return in;
}

}  // namespace at::db
