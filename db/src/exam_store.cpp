#include "db/exam_store.h"

#include <nlohmann/json.hpp>

#include "database.h"
#include "learner_model.h"
#include "lessons/course_json.h"
#include "quiz/answer_json.h"

namespace at::db {

using namespace at::lessons;

namespace {

constexpr const char* kSelectAttempt =
    "SELECT id, user_id, exam_id, course_id, started_at, deadline_at, finished_at, score, passed FROM exam_attempts";

ExamAttempt readAttempt(const Statement& s) {
  ExamAttempt a;
  a.id = s.int64(0);
  a.userId = s.int64(1);
  a.examId = s.text(2);
  a.courseId = s.text(3);
  a.startedAt = s.int64(4);
  a.deadline = s.int64(5);
  if (!s.isNull(6)) a.finishedAt = s.int64(6);
  a.score = s.optionalReal(7).value_or(0);
  if (!s.isNull(8)) a.passed = s.integer(8) != 0;
  return a;
}

Result<std::vector<ExamAttempt>> selectAttempts(Database& db, const std::string& where, const auto& bindAll) {
  auto s = db.prepare(std::string(kSelectAttempt) + " " + where);
  if (!s) return tl::unexpected(s.error());
  bindAll(*s);
  std::vector<ExamAttempt> out;
  while (true) {
    auto row = s->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) break;
    out.push_back(readAttempt(*s));
  }
  return out;
}

std::string sceneJson(const QuestionScene& scene) {
  return nlohmann::json{{"structure", scene.structure}, {"preset", scene.presetId}, {"view", toString(scene.view)}}.dump();
}

Result<QuestionScene> parseScene(const std::string& text, const std::string& where) {
  const auto j = nlohmann::json::parse(text, nullptr, false);
  if (!j.is_object() || !j.contains("structure") || !j["structure"].is_string() || !j.contains("view") ||
      !j["view"].is_string())
    return fail(where + ": stored scene is not {structure, preset, view}");
  auto view = parseCameraView(j["view"].get<std::string>());
  if (!view) return fail(where + ": " + view.error().message);
  QuestionScene scene;
  scene.structure = j["structure"].get<std::string>();
  scene.presetId = j.value("preset", std::string());
  scene.view = *view;
  return scene;
}

}  // namespace

Result<std::optional<ExamAttempt>> SqlExamRepository::openExamAttempt(std::int64_t userId, const std::string& examId) {
  auto found = selectAttempts(db_, "WHERE user_id = ?1 AND exam_id = ?2 AND finished_at IS NULL ORDER BY id DESC LIMIT 1",
                              [&](Statement& s) { s.bind(1, userId).bind(2, examId); });
  if (!found) return tl::unexpected(found.error());
  if (found->empty()) return std::optional<ExamAttempt>{};
  return std::optional<ExamAttempt>(found->front());
}

Result<ExamAttempt> SqlExamRepository::startExamAttempt(const ExamAttempt& attempt, std::vector<ExamItem>& items) {
  ExamAttempt a = attempt;
  auto status = db_.writeTransaction([&](Database& d) -> Status {
    auto insert = d.prepare(
        "INSERT INTO exam_attempts (user_id, exam_id, course_id, started_at, deadline_at) VALUES (?1, ?2, ?3, ?4, ?5)"
        " RETURNING id");
    if (!insert) return tl::unexpected(insert.error());
    insert->bind(1, a.userId).bind(2, a.examId).bind(3, a.courseId).bind(4, a.startedAt).bind(5, a.deadline);
    auto inserted = insert->insertReturningId();
    if (!inserted) {
      if (inserted.error().kind == ErrorKind::NotFound) return fail(ErrorKind::NotFound, "unknown user id " + std::to_string(a.userId));
      return tl::unexpected(inserted.error());
    }
    a.id = *inserted;
    auto item = d.prepare(
        "INSERT INTO exam_items (attempt_id, position, question_id, kind, structure, question, choices, key_choice,"
        " locate_view, scene) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10) RETURNING id");
    if (!item) return tl::unexpected(item.error());
    for (ExamItem& x : items) {
      const quiz::Question& q = x.question.question;
      item->reset();
      item->bind(1, a.id)
          .bind(2, x.position)
          .bind(3, q.id)
          .bind(4, quiz::toString(q.kind))
          .bind(5, q.target)
          .bind(6, questionToJson(q))
          .bind(7, nlohmann::json(x.question.choices).dump())
          .bind(8, x.question.keyChoice)
          .bind(9, toString(x.locateView))
          .bind(10, sceneJson(x.scene));
      auto itemId = item->insertReturningId();
      if (!itemId) return tl::unexpected(itemId.error());
      x.id = *itemId;
    }
    return {};
  });
  if (!status) return fail("starting exam '" + a.examId + "': " + status.error().message);
  return a;
}

Result<std::vector<ExamItem>> SqlExamRepository::examItems(std::int64_t attemptId) {
  auto s = db_.prepare(
      "SELECT id, position, question, choices, key_choice, locate_view, scene, answer, correct, score, latency_ms,"
      " answered_at FROM exam_items WHERE attempt_id = ?1 ORDER BY position");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, attemptId);
  std::vector<ExamItem> out;
  while (true) {
    auto row = s->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) break;
    ExamItem x;
    x.id = s->int64(0);
    x.position = s->integer(1);
    const std::string where = "exam item " + std::to_string(x.id);
    auto q = parseQuestionJson(s->text(2), where);
    if (!q) return tl::unexpected(q.error());
    x.question.question = std::move(*q);
    const auto choices = nlohmann::json::parse(s->text(3), nullptr, false);
    if (!choices.is_array()) return fail(where + ": stored choices are not a JSON list");
    for (const auto& c : choices) {
      if (!c.is_string()) return fail(where + ": stored choices are not structure ids");
      x.question.choices.push_back(c.get<std::string>());
    }
    x.question.keyChoice = s->integer(4);
    auto view = parseExamLocateView(s->text(5));
    if (!view) return fail(where + ": " + view.error().message);
    x.locateView = *view;
    auto scene = parseScene(s->text(6), where);
    if (!scene) return tl::unexpected(scene.error());
    x.scene = *scene;
    if (!s->isNull(7)) {
      auto answer = quiz::answerFromJson(s->text(7));
      if (!answer) return fail(where + ": " + answer.error().message);
      x.answer = std::move(*answer);
      x.correct = s->integer(8) != 0;
      x.score = s->optionalReal(9).value_or(0);
      x.latencyMs = s->isNull(10) ? 0 : s->int64(10);
      x.answeredAt = s->isNull(11) ? 0 : s->int64(11);
    }
    out.push_back(std::move(x));
  }
  return out;
}

Status SqlExamRepository::recordExamAnswer(const ExamAnswerRecord& record) {
  const GradedAnswer& g = record.answer;
  auto status = db_.writeTransaction([&](Database& d) -> Status {
    auto update = d.prepare(
        "UPDATE exam_items SET answer = ?3, correct = ?4, score = ?5, latency_ms = ?6, answered_at = ?7"
        " WHERE attempt_id = ?1 AND position = ?2 AND answer IS NULL AND question_id = ?8");
    if (!update) return tl::unexpected(update.error());
    update->bind(1, record.attemptId)
        .bind(2, record.position)
        .bind(3, quiz::answerToJson(g.answer))
        .bind(4, g.correct ? 1 : 0)
        .bind(5, g.score)
        .bind(6, g.latencyMs)
        .bind(7, g.answeredAt)
        .bind(8, g.questionId);
    if (auto s = update->run(); !s) return s;
    if (d.changes() != 1)
      return fail("exam item " + std::to_string(record.position + 1) + " of attempt " +
                  std::to_string(record.attemptId) + " is already answered or does not exist");
    auto id = d.prepare("SELECT id FROM exam_items WHERE attempt_id = ?1 AND position = ?2");
    if (!id) return tl::unexpected(id.error());
    id->bind(1, record.attemptId).bind(2, record.position);
    auto row = id->step();
    if (!row) return tl::unexpected(row.error());
    return writeLearnerModel(d, record.update, g, AnswerSource::Exam, id->int64(0));
  });
  if (!status) return fail("recording the exam answer: " + status.error().message);
  return {};
}

Status SqlExamRepository::finishExamAttempt(std::int64_t attemptId, UnixSeconds finishedAt, double score,
                                               std::optional<bool> passed) {
  return db_.writeTransaction([&](Database& d) -> Status {
    auto update = d.prepare("UPDATE exam_attempts SET finished_at = ?2, score = ?3, passed = ?4 WHERE id = ?1");
    if (!update) return tl::unexpected(update.error());
    update->bind(1, attemptId).bind(2, finishedAt).bind(3, score);
    if (passed) update->bind(4, *passed ? 1 : 0);
    else update->bindNull(4);
    if (auto s = update->run(); !s) return s;
    if (d.changes() != 1) return fail("unknown exam attempt " + std::to_string(attemptId));
    return {};
  });
}

Result<std::vector<ExamAttempt>> SqlExamRepository::examAttempts(std::int64_t userId) {
  return selectAttempts(db_, "WHERE user_id = ?1 ORDER BY id DESC", [&](Statement& s) { s.bind(1, userId); });
}

Result<std::vector<ExamAttempt>> SqlExamRepository::courseExamAttempts(const std::string& courseId) {
  return selectAttempts(db_, "WHERE course_id = ?1 ORDER BY id", [&](Statement& s) { s.bind(1, courseId); });
}

}  // namespace at::db
