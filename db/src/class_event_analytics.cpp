#include "class_event_analytics.h"

#include "lessons/exam.h"

#include <algorithm>
#include <map>

#include <nlohmann/json.hpp>

namespace at::db {

using namespace at::lessons;

Status addClassEventStudents(Database& db, AnalyticsInput& in, const std::set<std::string>& localNames,
                             const std::set<std::string>& courseQuestions, const std::optional<std::string>& classCode) {
  std::set<std::string> lessonIds;
  for (const Lesson& l : in.course.lessons) lessonIds.insert(l.id);
  // Student members (one row per person: the first class by code when in several).
  auto members = db.prepare(
      "SELECT user_name, MIN(class_code) FROM class_members WHERE role = 'student'" +
      std::string(classCode ? " AND class_code = ?1" : "") + " GROUP BY user_name ORDER BY user_name");
  if (!members) return tl::unexpected(members.error());
  if (classCode) members->bind(1, *classCode);
  std::map<std::string, std::int64_t> idOf;
  std::int64_t nextId = -1;
  auto status = forEachRow(*members, [&](Statement& r) -> Status {
    const std::string name = r.text(0);
    if (localNames.count(name)) return {};
    idOf[name] = nextId;
    in.students.push_back(User{nextId, name, Role::Student, r.text(1)});
    --nextId;
    return {};
  });
  if (!status) return status;
  if (idOf.empty()) return {};

  auto events = db.prepare(
      "SELECT user_name, kind, occurred_at, lesson_id, question_id, structure, correct, score, payload FROM class_events"
      " WHERE practice = 0" + std::string(classCode ? " AND class_code = ?1" : "") + " ORDER BY occurred_at, CASE kind WHEN 'lesson_started' THEN 0 WHEN 'answer' THEN 1 ELSE 2 END, received_at, uuid");
  if (!events) return tl::unexpected(events.error());
  if (classCode) events->bind(1, *classCode);
  // Events of one second in the order they happen in: a lesson starts, is answered, ends.
  std::int64_t order = 0, nextAttempt = -1;
  status = forEachRow(*events, [&](Statement& r) -> Status {
    const auto who = idOf.find(r.text(0));
    if (who == idOf.end()) return {};
    const std::string kind = r.text(1);
    const auto payload = nlohmann::json::parse(r.text(8), nullptr, false);
    const auto field = [&](const char* key) { return payload.is_object() && payload.contains(key) ? payload[key] : nlohmann::json(); };
    if (kind == "answer") {
      ClassAnswer a;
      a.userId = who->second;
      a.questionId = r.text(4);
      if (!courseQuestions.count(a.questionId)) return {};
      if (r.isNull(6)) {  // waiting for its key on the server: not evidence yet, as in class progress
        ++in.waitingAnswers;
        return {};
      }
      a.order = ++order;
      a.structureId = r.text(5);
      a.correct = r.integer(6) != 0;
      a.score = r.isNull(7) ? (a.correct ? 1.0 : 0.0) : r.real(7);
      a.answeredAt = r.int64(2);
      if (field("source").is_string())
        if (auto source = parseAnswerSource(field("source").get<std::string>())) a.source = *source;
      if (field("fsrs_rating").is_number_integer()) a.rating = Rating(std::clamp(field("fsrs_rating").get<int>(), 1, 4));
      if (field("latency_ms").is_number()) a.latencyMs = field("latency_ms").get<std::int64_t>();
      in.answers.push_back(std::move(a));
    } else if (kind == "lesson_started" && lessonIds.count(r.text(3))) {
      Attempt a;
      a.id = nextAttempt--;
      a.userId = who->second;
      a.lessonId = r.text(3);
      a.startedAt = r.int64(2);
      if (field("mode").is_string())
        if (auto mode = parseLessonMode(field("mode").get<std::string>())) a.mode = *mode;
      in.attempts.push_back(std::move(a));
    } else if (kind == "lesson_finished" && lessonIds.count(r.text(3))) {
      // The latest open attempt of that lesson by that student.
      for (auto it = in.attempts.rbegin(); it != in.attempts.rend(); ++it)
        if (it->userId == who->second && it->lessonId == r.text(3) && !it->finishedAt) {
          it->finishedAt = r.int64(2);
          it->score = r.isNull(7) ? 0 : r.real(7);
          it->scoreKnown = !r.isNull(7);
          break;
        }
    }
    return {};
  });
  if (!status || db.backend() != Backend::Postgres) return status;
  // Their exams graded on the class server (handed in), as attempts at the course's exams.
  auto sittings = db.prepare(
      "SELECT s.user_name, s.exam_id, s.started_at, s.deadline_at, s.finished_at, s.score, s.passed"
      " FROM class_exam_sittings s JOIN class_exams x ON x.class_code = s.class_code AND x.exam_id = s.exam_id"
      " WHERE x.course_id = ?1 AND s.finished_at IS NOT NULL" + std::string(classCode ? " AND s.class_code = ?2" : "") +
      " ORDER BY s.finished_at, s.user_name, s.exam_id");
  if (!sittings) return tl::unexpected(sittings.error());
  sittings->bind(1, in.course.id);
  if (classCode) sittings->bind(2, *classCode);
  std::int64_t nextSitting = -1;
  return forEachRow(*sittings, [&](Statement& r) -> Status {
    const auto who = idOf.find(r.text(0));
    if (who == idOf.end()) return {};
    ExamAttempt e;
    e.id = nextSitting--;
    e.userId = who->second;
    e.examId = r.text(1);
    e.courseId = in.course.id;
    e.startedAt = r.int64(2);
    e.deadline = r.int64(3);
    e.finishedAt = r.int64(4);
    e.score = r.isNull(5) ? 0 : r.real(5);
    if (!r.isNull(6)) e.passed = r.integer(6) != 0;
    in.examAttempts.push_back(std::move(e));
    return {};
  });
}

}  // namespace at::db
