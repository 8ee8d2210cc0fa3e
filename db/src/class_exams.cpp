#include "db/class_exams.h"

#include <set>

#include <nlohmann/json.hpp>

#include "database.h"
#include "quiz/sided_names.h"
#include "server_refusal.h"

namespace at::db {

namespace {

using nlohmann::json;

Status requireServer(Database& db) {
  if (db.backend() != Backend::Postgres)
    return fail("graded exams are held on a class server (postgresql://…), not in the local file " + db.path() +
                "; an exam taken there is practice");
  return {};
}

// Runs `sql` (one row, one column) and hands its statement to `read`; the server's refusal as the error.
template <class Read>
Status callServer(Database& d, const std::string& sql, const std::function<void(Statement&)>& bindAll, Read&& read) {
  auto s = d.prepare(sql);
  if (!s) return tl::unexpected(s.error());
  bindAll(*s);
  auto row = s->step();
  if (!row) return tl::unexpected(serverRefusal(row.error()));
  if (!*row) return fail(ErrorKind::Io, "the class server gave no answer to " + sql);
  read(*s);
  return {};
}

std::vector<std::string> stringArray(const std::string& text) {
  std::vector<std::string> out;
  const json parsed = json::parse(text, nullptr, false);
  if (parsed.is_array())
    for (const auto& v : parsed)
      if (v.is_string()) out.push_back(v.get<std::string>());
  return out;
}

}  // namespace

void setNameKey(ClassExamKey& key, const quiz::ResolvedQuestion& question, const quiz::GradingContext& context) {
  const quiz::Question& q = question.question;
  key.names.clear();
  if (const quiz::NameEntry* entry = context.entry(q.target)) key.names = entry->names;
  if (key.names.empty()) key.names.push_back(q.target);
  key.names.insert(key.names.end(), q.synonyms.begin(), q.synonyms.end());
  std::set<std::string> bodies, competitors;
  key.nameBodies.clear();
  for (const std::string& name : key.names)
    if (const std::string body = quiz::splitSide(name).body; !body.empty() && bodies.insert(body).second)
      key.nameBodies.push_back(body);  // in the names' order: the first closest spelling sets the allowance
  // The target's own spellings (and its base name) never compete: its counterpart on the other side.
  std::set<std::string> own = bodies;
  if (const quiz::NameEntry* entry = context.entry(q.target); entry && !entry->baseName.empty())
    own.insert(quiz::splitSide(entry->baseName).body);
  for (const quiz::NameEntry& entry : context.names) {
    if (entry.structureId == q.target) continue;
    for (const std::string& name : entry.names)
      if (const std::string body = quiz::splitSide(name).body; !body.empty() && !own.count(body)) competitors.insert(body);
  }
  key.competitorBodies.assign(competitors.begin(), competitors.end());
  const quiz::Side side = context.side(q.target);
  key.targetSide = quiz::toString(side);
  key.askSide = q.askSide && side != quiz::Side::None;
}

Result<int> openClassExam(Database& server, const std::string& code, const ClassExamOpening& exam,
                          const std::optional<std::string>& by) {
  if (auto ok = requireServer(server); !ok) return tl::unexpected(ok.error());
  if (exam.items.size() != exam.keys.size()) return fail("exam '" + exam.examId + "': one key per item is needed");
  json items = json::array(), keys = json::array();
  for (const ClassExamItem& i : exam.items) {
    json scene = json::parse(i.sceneJson, nullptr, false);
    if (scene.is_discarded()) return fail("exam '" + exam.examId + "': the scene of an item is not JSON");
    items.push_back({{"kind", i.kind}, {"prompt", i.prompt}, {"choices", i.choices}, {"locate_view", i.locateView},
                     {"scene", scene}, {"picture", i.pictureBase64}, {"picture_width", i.pictureWidth},
                     {"picture_height", i.pictureHeight}});
  }
  for (const ClassExamKey& k : exam.keys) {
    json runs = json::array();
    for (const PixelRun& r : k.acceptedPixels) runs.push_back({r.y, r.xFrom, r.xTo});
    keys.push_back({{"question_id", k.questionId}, {"target", k.target}, {"key_choice", k.keyChoice},
                    {"names", k.names}, {"tolerance_mm", k.toleranceMm}, {"accepted_pixels", runs},
                    {"name_bodies", k.nameBodies}, {"competitor_bodies", k.competitorBodies},
                    {"target_side", k.targetSide}, {"ask_side", k.askSide}});
  }
  int count = 0;
  auto status = server.writeTransaction([&](Database& d) -> Status {
    return callServer(
        d, "SELECT at_open_exam(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)",
        [&](Statement& s) {
          s.bind(1, code).bind(2, exam.examId).bind(3, exam.courseId).bind(4, exam.title).bind(5, exam.timeLimitS);
          s.bind(6, exam.passScore).bind(7, items.dump()).bind(8, keys.dump());
          s.bind(9, json(exam.prerequisites).dump()).bind(10, by.value_or(""));
        },
        [&](Statement& s) { count = s.integer(0); });
  });
  if (!status) return tl::unexpected(withContext("opening exam '" + exam.examId + "' in class " + code, status.error()));
  return count;
}

Result<int> closeClassExam(Database& server, const std::string& code, const std::string& examId,
                           const std::optional<std::string>& by) {
  if (auto ok = requireServer(server); !ok) return tl::unexpected(ok.error());
  int handedIn = 0;
  auto status = server.writeTransaction([&](Database& d) -> Status {
    return callServer(
        d, "SELECT at_close_exam(?1, ?2, ?3)",
        [&](Statement& s) { s.bind(1, code).bind(2, examId).bind(3, by.value_or("")); },
        [&](Statement& s) { handedIn = s.integer(0); });
  });
  if (!status) return tl::unexpected(status.error());
  return handedIn;
}

Result<bool> classExamOpen(Database& server, const std::string& code, const std::string& examId) {
  if (server.backend() != Backend::Postgres) return false;
  auto s = server.prepare("SELECT 1 FROM class_exams WHERE class_code = ?1 AND exam_id = ?2 AND closed_at IS NULL");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, code).bind(2, examId);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  return *row;
}

Result<ClassExamSitting> startClassExam(Database& server, const std::string& code, const std::string& examId,
                                        const std::optional<std::string>& by) {
  if (auto ok = requireServer(server); !ok) return tl::unexpected(ok.error());
  ClassExamSitting out;
  out.examId = examId;
  auto status = server.writeTransaction([&](Database& d) -> Status {
    return callServer(
        d, "SELECT at_start_exam(?1, ?2, ?3), extract(epoch FROM clock_timestamp())::bigint",
        [&](Statement& s) { s.bind(1, code).bind(2, examId).bind(3, by.value_or("")); },
        [&](Statement& s) {
          out.deadline = s.int64(0);
          out.serverNow = s.int64(1);
        });
  });
  if (!status) return tl::unexpected(status.error());
  auto exam = server.prepare(
      "SELECT x.title, x.pass_score, EXISTS (SELECT 1 FROM class_exam_sittings s WHERE s.class_code = x.class_code"
      " AND s.exam_id = x.exam_id AND s.user_name = coalesce(nullif(?3, ''), session_user::text) AND s.finished_at IS NOT NULL)"
      " FROM class_exams x WHERE x.class_code = ?1 AND x.exam_id = ?2");
  if (!exam) return tl::unexpected(exam.error());
  exam->bind(1, code).bind(2, examId).bind(3, by.value_or(""));
  if (auto row = exam->step(); !row) return tl::unexpected(row.error());
  else if (*row) {
    out.title = exam->text(0);
    out.passScore = exam->optionalReal(1);
    const std::string done = exam->text(2);
    out.handedIn = done == "t" || done == "true" || done == "1";
  }
  auto items = server.prepare(
      "SELECT position, kind, prompt, choices, locate_view, scene, picture, picture_width, picture_height"
      " FROM class_exam_items WHERE class_code = ?1 AND exam_id = ?2 ORDER BY position");
  if (!items) return tl::unexpected(items.error());
  items->bind(1, code).bind(2, examId);
  status = forEachRow(*items, [&](Statement& r) -> Status {
    out.items.push_back({r.integer(0), r.text(1), r.text(2), stringArray(r.text(3)), r.text(4), r.text(5), r.text(6),
                         r.integer(7), r.integer(8)});
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  // Which items this sitting answered (their grades stay unread until it is handed in).
  auto answered = server.prepare("SELECT at_exam_answered(?1, ?2, ?3)");
  if (!answered) return tl::unexpected(answered.error());
  answered->bind(1, code).bind(2, examId).bind(3, by.value_or(""));
  status = forEachRow(*answered, [&](Statement& r) -> Status {
    out.answered.insert(r.integer(0));
    return {};
  });
  if (!status) return tl::unexpected(serverRefusal(status.error()));
  return out;
}

Status answerClassExam(Database& server, const std::string& code, const std::string& examId, int position,
                       const ClassExamAnswer& answer, const std::optional<std::string>& by) {
  if (auto ok = requireServer(server); !ok) return ok;
  return server.writeTransaction([&](Database& d) -> Status {
    return callServer(
        d, "SELECT at_answer_exam(?1, ?2, ?3::integer, ?4::integer, ?5, ?6::integer, ?7::integer, ?8::bigint, ?9)",
        [&](Statement& s) {
          const auto some = [](std::optional<int> v) { return v ? std::optional<std::int64_t>(*v) : std::nullopt; };
          s.bind(1, code).bind(2, examId).bind(3, position);
          s.bind(4, some(answer.choice)).bind(5, answer.text);
          s.bind(6, some(answer.pixel ? std::optional<int>((*answer.pixel)[0]) : std::nullopt));
          s.bind(7, some(answer.pixel ? std::optional<int>((*answer.pixel)[1]) : std::nullopt));
          s.bind(8, answer.latencyMs);
          s.bind(9, by.value_or(""));
        },
        [](Statement&) {});
  });
}

Result<ClassExamResult> finishClassExam(Database& server, const std::string& code, const std::string& examId,
                                        const std::optional<std::string>& by) {
  if (auto ok = requireServer(server); !ok) return tl::unexpected(ok.error());
  ClassExamResult out;
  std::string member;
  auto status = server.writeTransaction([&](Database& d) -> Status {
    return callServer(
        d, "SELECT at_finish_exam(?1, ?2, ?3), s.passed, s.user_name FROM class_exam_sittings s"
           " WHERE s.class_code = ?1 AND s.exam_id = ?2 AND s.user_name = coalesce(nullif(?3, ''), session_user::text)",
        [&](Statement& s) { s.bind(1, code).bind(2, examId).bind(3, by.value_or("")); },
        [&](Statement& s) {
          out.score = s.real(0);
          member = s.text(2);
        });
  });
  if (!status) return tl::unexpected(status.error());
  auto sitting = server.prepare(
      "SELECT passed FROM class_exam_sittings WHERE class_code = ?1 AND exam_id = ?2 AND user_name = ?3");
  if (!sitting) return tl::unexpected(sitting.error());
  sitting->bind(1, code).bind(2, examId).bind(3, member);
  if (auto row = sitting->step(); !row) return tl::unexpected(row.error());
  else if (*row && !sitting->isNull(0)) out.passed = sitting->integer(0) != 0;
  auto items = server.prepare(
      "SELECT i.position, a.position IS NOT NULL, coalesce(a.correct, 0), coalesce(a.score, 0)"
      " FROM class_exam_items i LEFT JOIN class_exam_answers a ON a.class_code = i.class_code"
      " AND a.exam_id = i.exam_id AND a.position = i.position AND a.user_name = ?3"
      " WHERE i.class_code = ?1 AND i.exam_id = ?2 ORDER BY i.position");
  if (!items) return tl::unexpected(items.error());
  items->bind(1, code).bind(2, examId).bind(3, member);
  status = forEachRow(*items, [&](Statement& r) -> Status {
    const std::string answered = r.text(1);
    out.items.push_back({r.integer(0), answered == "t" || answered == "true" || answered == "1", r.integer(2) != 0,
                         r.real(3)});
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

Result<std::vector<ClassExamSittingRow>> classExamSittings(Database& server, const std::string& code) {
  std::vector<ClassExamSittingRow> out;
  if (server.backend() != Backend::Postgres) return out;
  auto s = server.prepare(
      "SELECT s.user_name, s.exam_id, x.course_id, s.started_at, s.finished_at, s.score, s.passed"
      " FROM class_exam_sittings s JOIN class_exams x ON x.class_code = s.class_code AND x.exam_id = s.exam_id"
      " WHERE s.class_code = ?1 ORDER BY s.user_name, s.started_at, s.exam_id");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, code);
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    ClassExamSittingRow row{r.text(0), r.text(1), r.text(2), r.int64(3), std::nullopt, r.optionalReal(5), std::nullopt};
    if (!r.isNull(4)) row.finishedAt = r.int64(4);
    if (!r.isNull(6)) row.passed = r.integer(6) != 0;
    out.push_back(std::move(row));
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

Result<std::vector<ClassExamAnswerRow>> classExamAnswers(Database& server, const std::string& code) {
  std::vector<ClassExamAnswerRow> out;
  if (server.backend() != Backend::Postgres) return out;
  auto s = server.prepare(
      "SELECT a.user_name, a.exam_id, a.position, i.kind, i.choices, a.answer, a.correct, a.score, a.latency_ms,"
      " a.answered_at FROM class_exam_answers a JOIN class_exam_items i ON i.class_code = a.class_code"
      " AND i.exam_id = a.exam_id AND i.position = a.position WHERE a.class_code = ?1"
      " ORDER BY a.user_name, a.exam_id, a.position");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, code);
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    out.push_back({r.text(0), r.text(1), r.integer(2), r.text(3), stringArray(r.text(4)), r.text(5), r.integer(6) != 0,
                   r.real(7), r.int64(8), r.int64(9)});
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

}  // namespace at::db
