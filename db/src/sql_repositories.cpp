#include "db/sql_repositories.h"

#include <nlohmann/json.hpp>

#include "class_events.h"
#include "database.h"
#include "db/dataset_store.h"
#include "learner_model.h"
#include "lessons/course_json.h"
#include "quiz/answer_json.h"

namespace at::db {

using namespace at::lessons;

namespace {

// The graded-answer columns, in the order both answer tables (responses, review_responses) have
// them after their own key columns.
constexpr const char* kGradedAnswerColumns =
    "question_id, structure, answer, correct, score, latency_ms, preset_id, mode, t, alpha, beta, answered_at";

// Binds a graded answer's 12 columns to parameters first … first + 11.
void bindGradedAnswer(Statement& s, int first, const GradedAnswer& g) {
  s.bind(first, g.questionId)
      .bind(first + 1, g.structureId)
      .bind(first + 2, quiz::answerToJson(g.answer))
      .bind(first + 3, g.correct ? 1 : 0)
      .bind(first + 4, g.score)
      .bind(first + 5, g.latencyMs)
      .bind(first + 6, g.render.presetId)
      .bind(first + 7, g.render.mode)
      .bind(first + 8, g.render.t)
      .bind(first + 9, g.render.alpha)
      .bind(first + 10, g.render.beta)
      .bind(first + 11, g.answeredAt);
}

// Reads a graded answer from result columns first … first + 11; `row` names the row in errors.
Status readGradedAnswer(const Statement& r, int first, const std::string& row, GradedAnswer& g) {
  g.questionId = r.text(first);
  g.structureId = r.text(first + 1);
  auto answer = quiz::answerFromJson(r.text(first + 2));
  if (!answer) return tl::unexpected(withContext(row, answer.error()));
  g.answer = std::move(*answer);
  g.correct = r.integer(first + 3) != 0;
  g.score = r.real(first + 4);
  g.latencyMs = r.int64(first + 5);
  g.render.presetId = r.text(first + 6);
  g.render.mode = r.text(first + 7);
  g.render.t = r.optionalReal(first + 8).value_or(0);
  g.render.alpha = r.optionalReal(first + 9).value_or(0);
  g.render.beta = r.optionalReal(first + 10).value_or(0);
  g.answeredAt = r.int64(first + 11);
  return {};
}


// The outbox event of a graded answer (class_server.h): the answer with everything graded and
// shown, its FSRS rating, and where it was given (a lesson step, or a review).
ClassEvent answerEvent(const GradedAnswer& g, const LearnerUpdate& u, AnswerSource source, const std::string& lessonId,
                       std::optional<int> stepIndex) {
  nlohmann::json payload = {
      {"source", toString(source)},
      {"lesson", lessonId},
      {"question", g.questionId},
      {"structure", g.structureId},
      {"answer", nlohmann::json::parse(quiz::answerToJson(g.answer), nullptr, false)},
      {"correct", g.correct},
      {"score", g.score},
      {"latency_ms", g.latencyMs},
      {"render", {{"preset", g.render.presetId}, {"mode", g.render.mode}, {"t", g.render.t},
                  {"alpha", g.render.alpha}, {"beta", g.render.beta}}},
      {"fsrs_rating", int(u.rating)},
      {"answered_at", g.answeredAt}};
  if (stepIndex) payload["step"] = *stepIndex;
  ClassEvent e;
  e.kind = "answer";
  e.occurredAt = g.answeredAt;
  e.lessonId = lessonId;
  e.questionId = g.questionId;
  e.structure = g.structureId;
  e.correct = g.correct ? 1 : 0;
  e.score = g.score;
  e.payload = payload.dump();
  return e;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Curriculum

SqlCurriculumRepository::SqlCurriculumRepository(Database& db, BuiltinStructures builtin)
    : db_(db), builtin_(std::move(builtin)) {}

Result<std::vector<Course>> SqlCurriculumRepository::courses() {
  auto s = db_.prepare("SELECT id FROM courses ORDER BY title, id");
  if (!s) return tl::unexpected(s.error());
  std::vector<std::string> ids;
  if (auto st = forEachRow(*s, [&](Statement& r) -> Status { ids.push_back(r.text(0)); return {}; }); !st)
    return tl::unexpected(st.error());
  std::vector<Course> out;
  for (const auto& id : ids) {
    auto c = course(id);
    if (!c && c.error().kind == ErrorKind::Io) return tl::unexpected(c.error());  // the database itself fails
    if (!c) {
      skip("course '" + id + "' is damaged in the database and was left out: " + c.error().message);
      continue;
    }
    out.push_back(std::move(*c));
  }
  return out;
}

void SqlCurriculumRepository::skip(const std::string& what) {
  if (skippedEver_.insert(what).second) skippedNew_.push_back(what);
}

std::vector<std::string> SqlCurriculumRepository::takeSkipped() {
  std::vector<std::string> out;
  out.swap(skippedNew_);
  return out;
}

Result<Course> SqlCurriculumRepository::course(const std::string& courseId) {
  auto s = db_.prepare("SELECT id, title, summary, dataset, version, synonyms FROM courses WHERE id = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, courseId);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return fail(ErrorKind::NotFound, "unknown course '" + courseId + "'");
  Course c;
  c.id = s->text(0);
  c.title = s->text(1);
  c.summary = s->text(2);
  c.datasetId = s->text(3);
  c.version = s->integer(4);
  const auto synonyms = nlohmann::json::parse(s->text(5), nullptr, false);
  if (!synonyms.is_object()) return fail("course '" + courseId + "': stored synonyms are not a JSON object");
  for (const auto& [structure, names] : synonyms.items()) {
    if (!names.is_array()) return fail("course '" + courseId + "': stored synonyms of '" + structure + "' are not a list");
    for (const auto& n : names) {
      if (!n.is_string()) return fail("course '" + courseId + "': a stored synonym of '" + structure + "' is not text");
      c.synonyms[structure].push_back(n.get<std::string>());
    }
  }

  auto ls = db_.prepare("SELECT id FROM lessons WHERE course_id = ?1 ORDER BY position");
  if (!ls) return tl::unexpected(ls.error());
  ls->bind(1, courseId);
  std::vector<std::string> ids;
  if (auto st = forEachRow(*ls, [&](Statement& r) -> Status { ids.push_back(r.text(0)); return {}; }); !st)
    return tl::unexpected(st.error());
  for (const auto& id : ids) {
    auto l = lesson(id);
    if (!l && l.error().kind == ErrorKind::Io) return tl::unexpected(l.error());  // the database itself fails
    if (!l) {
      skip("lesson '" + id + "' of course '" + courseId + "' is damaged in the database and was left out: " +
           l.error().message);
      continue;
    }
    c.lessons.push_back(std::move(*l));
  }
  auto exams = db_.prepare("SELECT id, json FROM exams WHERE course_id = ?1 ORDER BY position");
  if (!exams) return tl::unexpected(exams.error());
  exams->bind(1, courseId);
  auto status = forEachRow(*exams, [&](Statement& r) -> Status {
    auto exam = parseExamJson(r.text(1), "exam '" + r.text(0) + "'");
    if (!exam) return tl::unexpected(exam.error());
    c.exams.push_back(std::move(*exam));
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return c;
}

Result<Lesson> SqlCurriculumRepository::lesson(const std::string& lessonId) {
  auto s = db_.prepare("SELECT id, course_id, title, summary FROM lessons WHERE id = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, lessonId);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return fail(ErrorKind::NotFound, "unknown lesson '" + lessonId + "'");
  Lesson l;
  l.id = s->text(0);
  l.courseId = s->text(1);
  l.title = s->text(2);
  l.summary = s->text(3);

  auto pre = db_.prepare("SELECT requires_id FROM lesson_prerequisites WHERE lesson_id = ?1 ORDER BY position");
  if (!pre) return tl::unexpected(pre.error());
  pre->bind(1, lessonId);
  if (auto st = forEachRow(*pre, [&](Statement& r) -> Status { l.prerequisites.push_back(r.text(0)); return {}; }); !st)
    return tl::unexpected(st.error());

  auto steps = db_.prepare(
      "SELECT s.kind, s.structure, s.preset_id, s.view, s.title, s.text, s.study_items, q.json, s.placement"
      " FROM steps s LEFT JOIN questions q ON q.id = s.question_id WHERE s.lesson_id = ?1 ORDER BY s.position");
  if (!steps) return tl::unexpected(steps.error());
  steps->bind(1, lessonId);
  auto status = forEachRow(*steps, [&](Statement& r) -> Status {
    Step step;
    auto kind = parseStepKind(r.text(0));
    if (!kind) return tl::unexpected(kind.error());
    step.kind = *kind;
    const std::string where = "lesson '" + lessonId + "' step " + std::to_string(l.steps.size());
    switch (step.kind) {
      case StepKind::Show: {
        step.show.structure = r.text(1);
        step.show.presetId = r.text(2);
        auto view = parseCameraView(r.text(3));
        if (!view) return tl::unexpected(withContext(where, view.error()));
        step.show.view = *view;
        step.show.title = r.text(4);
        step.show.text = r.text(5);
        if (auto ok = parsePlacementJson(r.isNull(8) ? "" : r.text(8), where, step.show.camera, step.show.clip); !ok)
          return tl::unexpected(ok.error());
        break;
      }
      case StepKind::Question: {
        if (r.isNull(7)) return fail(where + ": its question is missing");
        auto q = parseQuestionJson(r.text(7), where);
        if (!q) return tl::unexpected(q.error());
        step.question = std::move(*q);
        if (!r.text(3).empty()) {  // the scene the course set (course_store.cpp)
          auto view = parseCameraView(r.text(3));
          if (!view) return fail(where + ": " + view.error().message);
          step.scene = QuestionScene{r.text(1), r.text(2), *view, std::nullopt, std::nullopt};
          if (auto ok = parsePlacementJson(r.isNull(8) ? "" : r.text(8), where, step.scene->camera, step.scene->clip); !ok)
            return tl::unexpected(ok.error());
        }
        break;
      }
      case StepKind::Study: {
        step.study.structure = r.text(1);
        const auto items = nlohmann::json::parse(r.text(6), nullptr, false);
        if (!items.is_array()) return fail(where + ": stored study items are not a JSON list");
        for (const auto& item : items) {
          if (!item.is_string()) return fail(where + ": a stored study item is not text");
          step.study.items.push_back(item.get<std::string>());
        }
        break;
      }
    }
    l.steps.push_back(std::move(step));
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return l;
}

Result<quiz::Question> SqlCurriculumRepository::question(const std::string& questionId) {
  auto s = db_.prepare("SELECT json FROM questions WHERE id = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, questionId);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return fail(ErrorKind::NotFound, "unknown question '" + questionId + "'");
  return parseQuestionJson(s->text(0), "question '" + questionId + "'");
}

Result<std::vector<Structure>> SqlCurriculumRepository::structures(const std::string& datasetId) {
  if (builtin_) {
    if (auto found = builtin_(datasetId)) return std::move(*found);
  }
  auto record = findDataset(db_, datasetId);
  if (!record) return tl::unexpected(record.error());
  if (!*record) return fail(ErrorKind::NotFound, "unknown dataset '" + datasetId + "' (import it with `anatomy-tutor import`)");
  return datasetStructures(db_, (*record)->id);
}

// ---------------------------------------------------------------------------------------------
// Users

namespace {

Result<User> readUser(const Statement& s) {
  User u;
  u.id = s.int64(0);
  u.name = s.text(1);
  auto role = parseRole(s.text(2));
  if (!role) return tl::unexpected(role.error());
  u.role = *role;
  u.group = s.text(3);
  return u;
}

constexpr const char* kSelectUser = "SELECT id, name, role, group_name FROM users";

}  // namespace

Result<std::optional<User>> SqlUserRepository::findUser(const std::string& name) {
  auto s = db_.prepare(std::string(kSelectUser) + " WHERE name = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, name);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return std::optional<User>{};
  auto u = readUser(*s);
  if (!u) return tl::unexpected(u.error());
  return std::optional<User>(std::move(*u));
}

Result<User> SqlUserRepository::user(std::int64_t userId) {
  auto s = db_.prepare(std::string(kSelectUser) + " WHERE id = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, userId);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return fail(ErrorKind::NotFound, "unknown user id " + std::to_string(userId));
  return readUser(*s);
}

Result<User> SqlUserRepository::createUser(const std::string& name, Role role, const std::string& group) {
  if (name.empty()) return fail("a user name must not be empty");
  User u{0, name, role, group};
  auto status = db_.writeTransaction([&](Database& d) -> Status {
    auto taken = d.prepare("SELECT 1 FROM users WHERE name = ?1");
    if (!taken) return tl::unexpected(taken.error());
    taken->bind(1, name);
    auto row = taken->step();
    if (!row) return tl::unexpected(row.error());
    if (*row) return fail(ErrorKind::Conflict, "the user name '" + name + "' is already taken");
    auto insert = d.prepare("INSERT INTO users (name, role, group_name) VALUES (?1, ?2, ?3) RETURNING id");
    if (!insert) return tl::unexpected(insert.error());
    insert->bind(1, name).bind(2, toString(role)).bind(3, group);
    auto inserted = insert->insertReturningId();
    if (!inserted) return tl::unexpected(inserted.error());
    u.id = *inserted;
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return u;
}

Result<std::vector<User>> SqlUserRepository::users() {
  auto s = db_.prepare(std::string(kSelectUser) + " ORDER BY name");
  if (!s) return tl::unexpected(s.error());
  std::vector<User> out;
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    auto u = readUser(r);
    if (!u) return tl::unexpected(u.error());
    out.push_back(std::move(*u));
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

// ---------------------------------------------------------------------------------------------
// Progress

namespace {

constexpr const char* kSelectAttempt = "SELECT id, user_id, lesson_id, mode, started_at, finished_at, score FROM attempts";

Result<Attempt> readAttempt(const Statement& s) {
  Attempt a;
  a.id = s.int64(0);
  a.userId = s.int64(1);
  a.lessonId = s.text(2);
  auto mode = parseLessonMode(s.text(3));
  if (!mode) return tl::unexpected(mode.error());
  a.mode = *mode;
  a.startedAt = s.int64(4);
  if (!s.isNull(5)) a.finishedAt = s.int64(5);
  a.score = s.real(6);
  return a;
}

constexpr const char* kSelectProgress =
    "SELECT user_id, structure, phase, step, stability, difficulty, due_at, last_review_at, reviews, lapses,"
    " answered, correct FROM memory_states";

Result<StructureProgress> readProgress(const Statement& s) {
  StructureProgress p;
  p.userId = s.int64(0);
  p.structureId = s.text(1);
  auto phase = parseMemoryPhase(s.text(2));
  if (!phase) return fail("memory state of '" + p.structureId + "': " + phase.error().message);
  p.memory.phase = *phase;
  p.memory.step = s.integer(3);
  p.memory.stability = s.real(4);
  p.memory.difficulty = s.real(5);
  p.memory.due = s.int64(6);
  p.memory.lastReview = s.int64(7);
  p.memory.reviews = s.integer(8);
  p.memory.lapses = s.integer(9);
  p.answered = s.integer(10);
  p.correct = s.integer(11);
  return p;
}

}  // namespace

Result<std::optional<Attempt>> SqlProgressRepository::openAttempt(std::int64_t userId, const std::string& lessonId) {
  auto s = db_.prepare(std::string(kSelectAttempt) +
                       " WHERE user_id = ?1 AND lesson_id = ?2 AND finished_at IS NULL ORDER BY id DESC LIMIT 1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, userId).bind(2, lessonId);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return std::optional<Attempt>{};
  auto a = readAttempt(*s);
  if (!a) return tl::unexpected(a.error());
  return std::optional<Attempt>(std::move(*a));
}

Result<Attempt> SqlProgressRepository::startAttempt(std::int64_t userId, const std::string& lessonId,
                                                       LessonMode mode, UnixSeconds startedAt) {
  Attempt a;
  a.userId = userId;
  a.lessonId = lessonId;
  a.mode = mode;
  a.startedAt = startedAt;
  auto status = db_.writeTransaction([&](Database& d) -> Status {
    auto insert = d.prepare("INSERT INTO attempts (user_id, lesson_id, mode, started_at) VALUES (?1, ?2, ?3, ?4) RETURNING id");
    if (!insert) return tl::unexpected(insert.error());
    insert->bind(1, userId).bind(2, lessonId).bind(3, toString(mode)).bind(4, startedAt);
    auto inserted = insert->insertReturningId();
    if (!inserted) return tl::unexpected(inserted.error());
    a.id = *inserted;
    ClassEvent started;
    started.kind = "lesson_started";
    started.occurredAt = startedAt;
    started.lessonId = lessonId;
    started.payload = nlohmann::json{{"lesson", lessonId}, {"mode", toString(mode)}, {"started_at", startedAt}}.dump();
    return enqueueClassEvent(d, userId, started);
  });
  if (!status) return tl::unexpected(withContext("starting lesson '" + lessonId + "'", status.error()));
  return a;
}

Status SqlProgressRepository::finishAttempt(std::int64_t attemptId, UnixSeconds finishedAt, double score) {
  return db_.writeTransaction([&](Database& d) -> Status {
    auto update = d.prepare("UPDATE attempts SET finished_at = ?2, score = ?3 WHERE id = ?1");
    if (!update) return tl::unexpected(update.error());
    update->bind(1, attemptId).bind(2, finishedAt).bind(3, score);
    if (auto s = update->run(); !s) return s;
    if (d.changes() != 1) return fail(ErrorKind::NotFound, "unknown attempt " + std::to_string(attemptId));
    auto attempt = d.prepare("SELECT user_id, lesson_id, mode, started_at FROM attempts WHERE id = ?1");
    if (!attempt) return tl::unexpected(attempt.error());
    attempt->bind(1, attemptId);
    auto row = attempt->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) return fail(ErrorKind::NotFound, "unknown attempt " + std::to_string(attemptId));
    ClassEvent finished;
    finished.kind = "lesson_finished";
    finished.occurredAt = finishedAt;
    finished.lessonId = attempt->text(1);
    finished.score = score;
    finished.payload = nlohmann::json{{"lesson", finished.lessonId}, {"mode", attempt->text(2)},
                                      {"started_at", attempt->int64(3)}, {"finished_at", finishedAt}, {"score", score}}
                           .dump();
    return enqueueClassEvent(d, attempt->int64(0), finished);
  });
}

Result<bool> SqlProgressRepository::hasFinished(std::int64_t userId, const std::string& lessonId) {
  auto s = db_.prepare(
      "SELECT EXISTS (SELECT 1 FROM attempts WHERE user_id = ?1 AND lesson_id = ?2 AND finished_at IS NOT NULL)");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, userId).bind(2, lessonId);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  return *row && s->integer(0) != 0;
}

Result<std::vector<Response>> SqlProgressRepository::responses(std::int64_t attemptId) {
  auto s = db_.prepare(std::string("SELECT id, attempt_id, step_index, ") + kGradedAnswerColumns +
                       " FROM responses WHERE attempt_id = ?1 ORDER BY id");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, attemptId);
  std::vector<Response> out;
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    Response x;
    x.id = r.int64(0);
    x.attemptId = r.int64(1);
    x.stepIndex = r.integer(2);
    if (Status st = readGradedAnswer(r, 3, "response " + std::to_string(x.id), x); !st) return st;
    out.push_back(std::move(x));
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

Result<std::int64_t> SqlProgressRepository::recordAnswer(const AnswerRecord& record) {
  const Response& r = record.response;
  const StructureProgress& p = record.update.progress;
  if (p.structureId != r.structureId)
    return fail("recording the answer: its progress is for another structure");
  std::int64_t id = 0;
  auto status = db_.writeTransaction([&](Database& d) -> Status {
    auto insert = d.prepare(std::string("INSERT INTO responses (attempt_id, step_index, ") + kGradedAnswerColumns +
                            ") VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14) RETURNING id");
    if (!insert) return tl::unexpected(insert.error());
    insert->bind(1, r.attemptId).bind(2, r.stepIndex);
    bindGradedAnswer(*insert, 3, r);
    auto inserted = insert->insertReturningId();
    if (!inserted) {
      if (inserted.error().kind == ErrorKind::Conflict)
        return fail(ErrorKind::Conflict, "step " + std::to_string(r.stepIndex) + " of attempt " + std::to_string(r.attemptId) +
                    " is already answered");
      if (inserted.error().kind == ErrorKind::NotFound)
        return fail(ErrorKind::NotFound, "unknown attempt " + std::to_string(r.attemptId));
      return tl::unexpected(inserted.error());
    }
    id = *inserted;
    if (auto st = writeLearnerModel(d, record.update, r, AnswerSource::Lesson, id); !st) return st;
    auto attempt = d.prepare("SELECT lesson_id FROM attempts WHERE id = ?1");
    if (!attempt) return tl::unexpected(attempt.error());
    attempt->bind(1, r.attemptId);
    auto row = attempt->step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) return fail(ErrorKind::NotFound, "unknown attempt " + std::to_string(r.attemptId));
    return enqueueClassEvent(d, p.userId, answerEvent(r, record.update, AnswerSource::Lesson, attempt->text(0), r.stepIndex));
  });
  if (!status) return tl::unexpected(withContext("recording the answer", status.error()));
  return id;
}

Result<std::int64_t> SqlProgressRepository::recordReviewAnswer(const ReviewRecord& record) {
  const ReviewResponse& r = record.response;
  const StructureProgress& p = record.update.progress;
  if (p.userId != r.userId || p.structureId != r.structureId)
    return fail("recording the review answer: its progress is for another user or structure");
  std::int64_t id = 0;
  auto status = db_.writeTransaction([&](Database& d) -> Status {
    auto insert = d.prepare(std::string("INSERT INTO review_responses (user_id, ") + kGradedAnswerColumns +
                            ") VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13) RETURNING id");
    if (!insert) return tl::unexpected(insert.error());
    insert->bind(1, r.userId);
    bindGradedAnswer(*insert, 2, r);
    auto inserted = insert->insertReturningId();
    if (!inserted) {
      if (inserted.error().kind == ErrorKind::NotFound)
        return fail(ErrorKind::NotFound, "unknown user id " + std::to_string(r.userId));
      return tl::unexpected(inserted.error());
    }
    id = *inserted;
    if (auto st = writeLearnerModel(d, record.update, r, AnswerSource::Review, id); !st) return st;
    return enqueueClassEvent(d, r.userId, answerEvent(r, record.update, AnswerSource::Review, "", std::nullopt));
  });
  if (!status) return tl::unexpected(withContext("recording the review answer", status.error()));
  return id;
}

Result<std::vector<ReviewResponse>> SqlProgressRepository::reviewResponses(std::int64_t userId) {
  auto s = db_.prepare(std::string("SELECT id, user_id, ") + kGradedAnswerColumns +
                       " FROM review_responses WHERE user_id = ?1 ORDER BY id");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, userId);
  std::vector<ReviewResponse> out;
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    ReviewResponse x;
    x.id = r.int64(0);
    x.userId = r.int64(1);
    if (Status st = readGradedAnswer(r, 2, "review response " + std::to_string(x.id), x); !st) return st;
    out.push_back(std::move(x));
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

Result<std::vector<ReviewLogEntry>> SqlProgressRepository::reviewLog(std::int64_t userId) {
  auto s = db_.prepare(
      "SELECT id, user_id, structure, question_id, source, reviewed_at, rating, correct, score, latency_ms,"
      " phase_before, elapsed_days, phase_after, stability, difficulty, due_at, rebuilt"
      " FROM review_log WHERE user_id = ?1 ORDER BY reviewed_at, id");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, userId);
  std::vector<ReviewLogEntry> out;
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    ReviewLogEntry e;
    e.id = r.int64(0);
    const std::string row = "review log entry " + std::to_string(e.id);
    e.userId = r.int64(1);
    e.structureId = r.text(2);
    e.questionId = r.text(3);
    auto source = parseAnswerSource(r.text(4));
    if (!source) return fail(row + ": " + source.error().message);
    e.source = *source;
    e.reviewedAt = r.int64(5);
    const int rating = r.integer(6);
    if (rating < 1 || rating > 4) return fail(row + ": rating " + std::to_string(rating) + " is not 1..4");
    e.rating = Rating(rating);
    e.correct = r.integer(7) != 0;
    e.score = r.real(8);
    e.latencyMs = r.int64(9);
    auto phase = parseMemoryPhase(r.text(10));
    if (!phase) return fail(row + ": " + phase.error().message);
    e.phaseBefore = *phase;
    e.elapsedDays = r.isNull(11) ? -1 : r.integer(11);
    e.rebuilt = r.integer(16) != 0;
    if (!r.isNull(12)) {
      auto after = parseMemoryPhase(r.text(12));
      if (!after) return fail(row + ": " + after.error().message);
      e.after.phase = *after;
      e.after.stability = r.optionalReal(13).value_or(0);
      e.after.difficulty = r.optionalReal(14).value_or(0);
      e.after.due = r.isNull(15) ? 0 : r.int64(15);
      e.after.lastReview = e.reviewedAt;
    }
    out.push_back(std::move(e));
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

Result<std::optional<StructureProgress>> SqlProgressRepository::progress(std::int64_t userId,
                                                                            const std::string& structureId) {
  auto s = db_.prepare(std::string(kSelectProgress) + " WHERE user_id = ?1 AND structure = ?2");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, userId).bind(2, structureId);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return std::optional<StructureProgress>{};
  auto p = readProgress(*s);
  if (!p) return tl::unexpected(p.error());
  return std::optional<StructureProgress>(std::move(*p));
}

Result<std::vector<StructureProgress>> SqlProgressRepository::allProgress(std::int64_t userId) {
  auto s = db_.prepare(std::string(kSelectProgress) + " WHERE user_id = ?1 ORDER BY structure");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, userId);
  std::vector<StructureProgress> out;
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    auto p = readProgress(r);
    if (!p) return tl::unexpected(p.error());
    out.push_back(std::move(*p));
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

Result<std::optional<double>> SqlProgressRepository::ability(std::int64_t userId) {
  auto s = db_.prepare("SELECT rating FROM user_ability WHERE user_id = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, userId);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return std::optional<double>{};
  return std::optional<double>(s->real(0));
}

Result<std::optional<double>> SqlProgressRepository::questionDifficulty(const std::string& questionId) {
  auto s = db_.prepare("SELECT difficulty FROM question_stats WHERE question_id = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, questionId);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return std::optional<double>{};
  return std::optional<double>(s->real(0));
}

Result<std::vector<Attempt>> SqlProgressRepository::attempts(std::int64_t userId) {
  auto s = db_.prepare(std::string(kSelectAttempt) + " WHERE user_id = ?1 ORDER BY id DESC");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, userId);
  std::vector<Attempt> out;
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    auto a = readAttempt(r);
    if (!a) return tl::unexpected(a.error());
    out.push_back(std::move(*a));
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

}  // namespace at::db
