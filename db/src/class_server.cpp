#include "db/class_server.h"

#include <algorithm>
#include <chrono>
#include <ctime>
#include <map>
#include <random>
#include <set>

#include "class_events.h"
#include "database.h"
#include "db/class_accounts.h"
#include "server_refusal.h"
#include "uuid.h"

namespace at::db {

namespace {

// Letters and digits a class code is made of: no I, O, 0 or 1, which read alike.
constexpr std::string_view kCodeAlphabet = "ABCDEFGHJKLMNPQRSTUVWXYZ23456789";
constexpr std::size_t kCodeLength = 8;

std::int64_t nowSeconds() { return std::int64_t(std::time(nullptr)); }

std::string newClassCode() {
  thread_local std::mt19937 generator{std::random_device{}()};
  std::uniform_int_distribution<std::size_t> pick(0, kCodeAlphabet.size() - 1);
  std::string code;
  for (std::size_t i = 0; i < kCodeLength; ++i) code += kCodeAlphabet[pick(generator)];
  return code;
}

Result<ClassInfo> readClass(Database& db, const std::string& code) {
  auto s = db.prepare("SELECT code, title, created_by FROM classes WHERE code = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, code);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return fail(ErrorKind::NotFound, "no class has the code " + code + " on " + db.path());
  return ClassInfo{s->text(0), s->text(1), s->text(2)};
}

Result<std::optional<ClassRole>> readRole(Database& db, const std::string& code, const std::string& userName) {
  auto s = db.prepare("SELECT role FROM class_members WHERE class_code = ?1 AND user_name = ?2");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, code).bind(2, userName);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return std::optional<ClassRole>{};
  auto role = parseClassRole(s->text(0));
  if (!role) return tl::unexpected(role.error());
  return std::optional<ClassRole>(*role);
}

Status requireUserName(const std::string& userName) {
  if (userName.empty()) return fail("a member's user name must not be empty");
  return {};
}

}  // namespace

const char* toString(ClassRole role) {
  switch (role) {
    case ClassRole::Student: return "student";
    case ClassRole::Instructor: return "instructor";
    case ClassRole::Coordinator: return "coordinator";
  }
  return "student";
}

Result<ClassRole> parseClassRole(const std::string& text) {
  if (text == "student") return ClassRole::Student;
  if (text == "instructor") return ClassRole::Instructor;
  if (text == "coordinator") return ClassRole::Coordinator;
  return fail("role '" + text + "' is not one of student, instructor, coordinator");
}

Result<std::string> normalizeClassCode(const std::string& text) {
  std::string code;
  for (char c : text) {
    if (c == '-' || c == ' ') continue;
    code += char(std::toupper(static_cast<unsigned char>(c)));
  }
  const bool known = std::all_of(code.begin(), code.end(), [](char c) { return kCodeAlphabet.find(c) != std::string_view::npos; });
  if (code.size() != kCodeLength || !known)
    return fail("class code '" + text + "' is not 8 letters and digits (as `class create` printed it, e.g. K7M2P9QX)");
  return code;
}

// ---------------------------------------------------------------------------------------------
// On the server

Result<ClassInfo> createClass(Database& server, const std::string& title, const std::string& creator) {
  if (title.empty()) return fail("a class title must not be empty");
  if (auto ok = requireUserName(creator); !ok) return tl::unexpected(ok.error());
  if (server.backend() == Backend::Postgres) {
    auto identity = serverIdentity(server);
    if (!identity) return tl::unexpected(identity.error());
    if (identity->account)
      return fail(ErrorKind::Conflict, "classes are made by the class server's administrator login, not by " +
                                           identity->login + " (a person's login)");
  }
  ClassInfo info{"", title, creator};
  auto status = server.writeTransaction([&](Database& d) -> Status {
    for (int tries = 0; tries < 16; ++tries) {
      const std::string code = newClassCode();
      auto insert = d.prepare("INSERT INTO classes (code, title, created_by) VALUES (?1, ?2, ?3) ON CONFLICT (code) DO NOTHING");
      if (!insert) return tl::unexpected(insert.error());
      insert->bind(1, code).bind(2, title).bind(3, creator);
      if (auto s = insert->run(); !s) return s;
      if (d.changes() == 0) continue;  // taken: draw again
      auto member = d.prepare("INSERT INTO class_members (class_code, user_name, role, joined_at) VALUES (?1, ?2, ?3, ?4)");
      if (!member) return tl::unexpected(member.error());
      member->bind(1, code).bind(2, creator).bind(3, toString(ClassRole::Coordinator)).bind(4, nowSeconds());
      if (auto s = member->run(); !s) return s;
      info.code = code;
      return {};
    }
    return fail(ErrorKind::Conflict, "no free class code found in 16 draws");
  });
  if (!status) return tl::unexpected(withContext("creating class '" + title + "'", status.error()));
  return info;
}

Result<ClassInfo> findClass(Database& server, const std::string& code) { return readClass(server, code); }

Result<ClassRole> joinClass(Database& server, const std::string& code, const std::string& userName) {
  if (auto ok = requireUserName(userName); !ok) return tl::unexpected(ok.error());
  if (server.backend() == Backend::Postgres) {
    auto identity = serverIdentity(server);
    if (!identity) return tl::unexpected(identity.error());
    if (identity->account) {  // a person's login joins nothing: a coordinator made them a member
      if (userName != identity->login)
        return fail(ErrorKind::Conflict, "you are logged in to the class server as " + identity->login + "; you cannot join as " + userName);
      auto role = memberRole(server, code, userName);
      if (!role && role.error().kind == ErrorKind::NotFound)
        return fail(ErrorKind::NotFound, identity->login + " is not a member of class " + code +
                                             " (ask its coordinator: `anatomy-tutor class account " + code + " " +
                                             identity->login + " --role student`)");
      return role;
    }
  }
  ClassRole role = ClassRole::Student;
  auto status = server.writeTransaction([&](Database& d) -> Status {
    if (auto found = readClass(d, code); !found) return tl::unexpected(found.error());
    auto insert = d.prepare("INSERT INTO class_members (class_code, user_name, role, joined_at) VALUES (?1, ?2, ?3, ?4)"
                            " ON CONFLICT (class_code, user_name) DO NOTHING");
    if (!insert) return tl::unexpected(insert.error());
    insert->bind(1, code).bind(2, userName).bind(3, toString(ClassRole::Student)).bind(4, nowSeconds());
    if (auto s = insert->run(); !s) return s;
    auto stored = readRole(d, code, userName);
    if (!stored) return tl::unexpected(stored.error());
    role = stored->value_or(ClassRole::Student);
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return role;
}

Result<ClassRole> memberRole(Database& server, const std::string& code, const std::string& userName) {
  auto info = readClass(server, code);
  if (!info) return tl::unexpected(info.error());
  auto role = readRole(server, code, userName);
  if (!role) return tl::unexpected(role.error());
  if (!*role) return fail(ErrorKind::NotFound, "'" + userName + "' is not a member of class " + code + " (" + info->title + ")");
  return **role;
}

Status setMemberRole(Database& server, const std::string& code, const std::string& by, const std::string& userName,
                     ClassRole role) {
  if (auto ok = requireUserName(userName); !ok) return ok;
  if (server.backend() == Backend::Postgres)  // audited, and the acting name is the login's
    return server.writeTransaction([&](Database& d) -> Status {
      auto call = d.prepare("SELECT at_set_role(?1, ?2, ?3, ?4)");
      if (!call) return tl::unexpected(call.error());
      call->bind(1, code).bind(2, userName).bind(3, toString(role)).bind(4, by);
      auto row = call->step();
      if (!row) return tl::unexpected(serverRefusal(row.error()));
      return {};
    });
  return server.writeTransaction([&](Database& d) -> Status {
    auto byRole = memberRole(d, code, by);
    if (!byRole) return tl::unexpected(byRole.error());
    if (*byRole != ClassRole::Coordinator)
      return fail(ErrorKind::Conflict, "'" + by + "' is " + toString(*byRole) + " of class " + code +
                                           "; only its coordinators give roles");
    auto upsert = d.prepare("INSERT INTO class_members (class_code, user_name, role, joined_at) VALUES (?1, ?2, ?3, ?4)"
                            " ON CONFLICT (class_code, user_name) DO UPDATE SET role = excluded.role");
    if (!upsert) return tl::unexpected(upsert.error());
    upsert->bind(1, code).bind(2, userName).bind(3, toString(role)).bind(4, nowSeconds());
    return upsert->run();
  });
}

Result<ClassProgress> classProgress(Database& server, const std::string& code, const std::string& claimedViewer) {
  auto acting = actingName(server, claimedViewer);
  if (!acting) return tl::unexpected(acting.error());
  const std::string& viewer = *acting;
  auto role = memberRole(server, code, viewer);
  if (!role) return tl::unexpected(role.error());
  if (*role == ClassRole::Student)
    return fail(ErrorKind::Conflict, "'" + viewer + "' is a student of class " + code +
                                         "; the class's progress is for its instructors and coordinators");
  ClassProgress out;
  auto info = readClass(server, code);
  if (!info) return tl::unexpected(info.error());
  out.info = *info;

  // One row per student member, computed from the events (none yet: a row of zeros). Answers and
  // right answers are the graded ones; those waiting for their keys and practice are counted apart.
  auto students = server.prepare(
      "SELECT m.user_name,"
      " SUM(CASE WHEN e.kind = 'answer' AND e.practice = 0 AND e.correct IS NOT NULL THEN 1 ELSE 0 END),"
      " SUM(CASE WHEN e.kind = 'answer' AND e.practice = 0 AND e.correct = 1 THEN 1 ELSE 0 END),"
      " COUNT(DISTINCT CASE WHEN e.kind = 'answer' AND e.practice = 0 AND e.correct IS NOT NULL THEN e.structure END),"
      " COUNT(DISTINCT CASE WHEN e.kind = 'lesson_started' THEN e.lesson_id END),"
      " COUNT(DISTINCT CASE WHEN e.kind = 'lesson_finished' THEN e.lesson_id END),"
      " MAX(e.occurred_at), MAX(m.withdrawal_reason),"
      " SUM(CASE WHEN e.kind = 'answer' AND e.practice = 1 THEN 1 ELSE 0 END),"
      " SUM(CASE WHEN e.kind = 'answer' AND e.practice = 0 AND e.correct IS NULL THEN 1 ELSE 0 END)"
      " FROM class_members m LEFT JOIN class_events e ON e.class_code = m.class_code AND e.user_name = m.user_name"
      " WHERE m.class_code = ?1 AND m.role = 'student' GROUP BY m.user_name ORDER BY m.user_name");
  if (!students) return tl::unexpected(students.error());
  students->bind(1, code);
  auto status = forEachRow(*students, [&](Statement& r) -> Status {
    StudentClassProgress p;
    p.userName = r.text(0);
    p.answers = r.integer(1);
    p.correct = r.integer(2);
    p.structures = r.integer(3);
    p.lessonsStarted = r.integer(4);
    p.lessonsFinished = r.integer(5);
    if (!r.isNull(6)) p.lastActive = r.int64(6);
    p.withdrawal = r.optionalText(7);
    p.practice = r.integer(8);
    p.ungraded = r.integer(9);
    out.students.push_back(std::move(p));
    return {};
  });
  if (!status) return tl::unexpected(status.error());

  // Graded exams handed in on the server (the table exists on a class server only).
  if (server.backend() == Backend::Postgres) {
    auto exams = server.prepare(
        "SELECT user_name, COUNT(*), AVG(score) FROM class_exam_sittings"
        " WHERE class_code = ?1 AND finished_at IS NOT NULL GROUP BY user_name");
    if (!exams) return tl::unexpected(exams.error());
    exams->bind(1, code);
    status = forEachRow(*exams, [&](Statement& r) -> Status {
      for (StudentClassProgress& p : out.students)
        if (p.userName == r.text(0)) {
          p.examsHandedIn = r.integer(1);
          p.examScore = r.optionalReal(2);
        }
      return {};
    });
    if (!status) return tl::unexpected(status.error());
  }

  auto structures = server.prepare(
      "SELECT structure, COUNT(DISTINCT user_name), COUNT(*), SUM(CASE WHEN correct = 1 THEN 1 ELSE 0 END)"
      " FROM class_events WHERE class_code = ?1 AND kind = 'answer' AND practice = 0 AND correct IS NOT NULL"
      " GROUP BY structure ORDER BY structure");
  if (!structures) return tl::unexpected(structures.error());
  structures->bind(1, code);
  status = forEachRow(*structures, [&](Statement& r) -> Status {
    out.structures.push_back({r.text(0), r.integer(1), r.integer(2), r.integer(3)});
    return {};
  });
  if (!status) return tl::unexpected(status.error());

  auto events = server.prepare("SELECT COUNT(*) FROM class_events WHERE class_code = ?1");
  if (!events) return tl::unexpected(events.error());
  events->bind(1, code);
  auto row = events->step();
  if (!row) return tl::unexpected(row.error());
  out.events = *row ? events->int64(0) : 0;
  return out;
}

// ---------------------------------------------------------------------------------------------
// On a learner's machine

Status rememberMembership(Database& local, const ClassMembership& m) {
  if (auto ok = requireUserName(m.userName); !ok) return ok;
  return local.writeTransaction([&](Database& d) -> Status {
    auto upsert = d.prepare(
        "INSERT INTO class_memberships (user_name, class_code, server, role, joined_at) VALUES (?1, ?2, ?3, ?4, ?5)"
        " ON CONFLICT (user_name) DO UPDATE SET class_code = excluded.class_code, server = excluded.server,"
        " role = excluded.role, joined_at = excluded.joined_at");
    if (!upsert) return tl::unexpected(upsert.error());
    upsert->bind(1, m.userName).bind(2, m.classCode).bind(3, m.server).bind(4, toString(m.role)).bind(5, nowSeconds());
    return upsert->run();
  });
}

Result<std::optional<ClassMembership>> membershipOf(Database& local, const std::string& userName) {
  auto s = local.prepare("SELECT user_name, class_code, server, role FROM class_memberships WHERE user_name = ?1");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, userName);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return std::optional<ClassMembership>{};
  auto role = parseClassRole(s->text(3));
  if (!role) return tl::unexpected(withContext("class membership of '" + userName + "'", role.error()));
  return std::optional<ClassMembership>(ClassMembership{s->text(0), s->text(1), s->text(2), *role});
}

Status enqueueClassEvent(Database& d, std::int64_t userId, const ClassEvent& e) {
  auto insert = d.prepare(
      "INSERT INTO outbox (uuid, server, class_code, user_name, kind, occurred_at, lesson_id, question_id, structure,"
      " correct, score, payload)"
      " SELECT ?1, m.server, m.class_code, m.user_name, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9"
      " FROM users u JOIN class_memberships m ON m.user_name = u.name WHERE u.id = ?10");
  if (!insert) return tl::unexpected(insert.error());
  insert->bind(1, newUuid())
      .bind(2, e.kind)
      .bind(3, e.occurredAt)
      .bind(4, e.lessonId)
      .bind(5, e.questionId)
      .bind(6, e.structure)
      .bind(7, e.correct ? std::optional<std::int64_t>(*e.correct) : std::nullopt)
      .bind(8, e.score)
      .bind(9, e.payload)
      .bind(10, userId);
  return insert->run();
}

Result<OutboxCounts> outboxCounts(Database& local) {
  auto s = local.prepare(
      "SELECT SUM(CASE WHEN sent_at IS NULL THEN 1 ELSE 0 END), SUM(CASE WHEN sent_at IS NULL THEN 0 ELSE 1 END),"
      " SUM(CASE WHEN refused IS NULL THEN 0 ELSE 1 END) FROM outbox");
  if (!s) return tl::unexpected(s.error());
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  OutboxCounts counts;
  if (*row && !s->isNull(0)) {
    counts.pending = s->int64(0);
    counts.sent = s->int64(1);
    counts.refused = s->int64(2);
  }
  return counts;
}

bool SyncReport::complete() const {
  return std::all_of(servers.begin(), servers.end(), [](const ServerSync& s) { return s.pending == 0 && !s.error; });
}

namespace {

struct PendingEvent {
  std::int64_t seq = 0;
  ClassEvent event;
  std::string uuid, classCode, userName;
};

Result<std::vector<PendingEvent>> pendingBatch(Database& local, const std::string& server, int limit) {
  auto s = local.prepare(
      "SELECT seq, uuid, class_code, user_name, kind, occurred_at, lesson_id, question_id, structure, correct, score,"
      " payload FROM outbox WHERE server = ?1 AND sent_at IS NULL ORDER BY seq LIMIT ?2");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, server).bind(2, limit);
  std::vector<PendingEvent> out;
  auto status = forEachRow(*s, [&](Statement& r) -> Status {
    PendingEvent p;
    p.seq = r.int64(0);
    p.uuid = r.text(1);
    p.classCode = r.text(2);
    p.userName = r.text(3);
    p.event.kind = r.text(4);
    p.event.occurredAt = r.int64(5);
    p.event.lessonId = r.text(6);
    p.event.questionId = r.text(7);
    p.event.structure = r.text(8);
    if (!r.isNull(9)) p.event.correct = r.integer(9);
    p.event.score = r.optionalReal(10);
    p.event.payload = r.text(11);
    out.push_back(std::move(p));
    return {};
  });
  if (!status) return tl::unexpected(status.error());
  return out;
}

Result<std::int64_t> pendingFor(Database& local, const std::string& server) {
  auto s = local.prepare("SELECT COUNT(*) FROM outbox WHERE server = ?1 AND sent_at IS NULL");
  if (!s) return tl::unexpected(s.error());
  s->bind(1, server);
  auto row = s->step();
  if (!row) return tl::unexpected(row.error());
  return *row ? s->int64(0) : 0;
}

// One batch into the server's class events, in one transaction, through the server's
// at_record_event: the server decides what counts (class_security_sql.cpp) and answers each event
// 'stored', 'repeated' (a UUID it has from this sender) or 'refused: <why>'. Appends keyed by UUID
// need no program-wide writer order, so this takes no writer lock (Deferred): clients push in
// parallel. `refusals` gets the refused events' sequence numbers and reasons.
Status pushBatch(Database& server, const std::vector<PendingEvent>& batch, ServerSync& report,
                 std::vector<std::pair<std::int64_t, std::string>>& refusals) {
  auto tx = Transaction::begin(server, Transaction::Kind::Deferred);
  if (!tx) return tl::unexpected(tx.error());
  std::int64_t pushed = 0, repeated = 0;
  std::vector<std::pair<std::int64_t, std::string>> refused;
  for (const PendingEvent& p : batch) {
    auto record = server.prepare("SELECT at_record_event(?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11)");
    if (!record) return tl::unexpected(record.error());
    record->bind(1, p.uuid)
        .bind(2, p.classCode)
        .bind(3, p.userName)
        .bind(4, p.event.kind)
        .bind(5, p.event.occurredAt)
        .bind(6, p.event.lessonId)
        .bind(7, p.event.questionId)
        .bind(8, p.event.structure)
        .bind(9, p.event.correct ? std::optional<std::int64_t>(*p.event.correct) : std::nullopt)
        .bind(10, p.event.score)
        .bind(11, p.event.payload);
    auto row = record->step();
    if (!row) return tl::unexpected(withContext("event " + p.uuid, serverRefusal(row.error())));
    const std::string outcome = *row ? record->text(0) : "refused: the server gave no answer";
    if (outcome == "stored") {
      ++pushed;
    } else if (outcome == "repeated") {
      ++repeated;
    } else {
      const std::string prefix = "refused: ";
      refused.emplace_back(p.seq, outcome.rfind(prefix, 0) == 0 ? outcome.substr(prefix.size()) : outcome);
    }
  }
  if (auto s = tx->commit(); !s) return s;
  report.pushed += pushed;
  report.repeated += repeated;
  report.refused += std::int64_t(refused.size());
  for (const auto& r : refused)
    if (report.refusals.size() < 5) report.refusals.push_back(r.second);
  refusals.insert(refusals.end(), refused.begin(), refused.end());
  return {};
}

// Marks the batch sent; a refused event keeps the server's reason and is not sent again.
Status markSent(Database& local, const std::string& server, std::int64_t firstSeq, std::int64_t lastSeq,
                const std::vector<std::pair<std::int64_t, std::string>>& refusals) {
  return local.writeTransaction([&](Database& d) -> Status {
    auto update = d.prepare(
        "UPDATE outbox SET sent_at = ?1 WHERE server = ?2 AND seq BETWEEN ?3 AND ?4 AND sent_at IS NULL");
    if (!update) return tl::unexpected(update.error());
    update->bind(1, nowSeconds()).bind(2, server).bind(3, firstSeq).bind(4, lastSeq);
    if (auto s = update->run(); !s) return s;
    for (const auto& [seq, reason] : refusals) {
      auto refuse = d.prepare("UPDATE outbox SET refused = ?1 WHERE seq = ?2");
      if (!refuse) return tl::unexpected(refuse.error());
      refuse->bind(1, reason).bind(2, seq);
      if (auto s = refuse->run(); !s) return s;
    }
    return {};
  });
}

}  // namespace

struct ServerConnections::Open {
  std::map<std::string, std::unique_ptr<Database>> byUrl;
};

ServerConnections::ServerConnections() : open_(std::make_unique<Open>()) {}
ServerConnections::~ServerConnections() = default;
ServerConnections::ServerConnections(ServerConnections&&) noexcept = default;
ServerConnections& ServerConnections::operator=(ServerConnections&&) noexcept = default;

Result<Database*> ServerConnections::get(const std::string& url, int connectTimeoutSeconds) {
  auto& slot = open_->byUrl[url];
  if (!slot) {
    OpenOptions open;
    open.create = false;
    open.connectTimeoutSeconds = connectTimeoutSeconds;
    auto server = Database::open(url, open);
    if (!server) {
      open_->byUrl.erase(url);
      return tl::unexpected(server.error());
    }
    slot = std::make_unique<Database>(std::move(*server));
  }
  return slot.get();
}

void ServerConnections::drop(const std::string& url) { open_->byUrl.erase(url); }

Result<SyncReport> syncOutbox(Database& local, const SyncOptions& options, ServerConnections* connections) {
  ServerConnections ownConnections;
  ServerConnections& open = connections ? *connections : ownConnections;
  SyncReport report;
  std::vector<std::string> servers;
  {
    auto s = local.prepare("SELECT server FROM outbox WHERE sent_at IS NULL GROUP BY server ORDER BY MIN(seq)");
    if (!s) return tl::unexpected(s.error());
    auto status = forEachRow(*s, [&](Statement& r) -> Status {
      servers.push_back(r.text(0));
      return {};
    });
    if (!status) return tl::unexpected(status.error());
  }
  for (const std::string& url : servers) {
    ServerSync entry;
    entry.server = withoutPassword(url);
    auto server = open.get(url, options.connectTimeoutSeconds);
    if (!server) {
      entry.error = server.error();
    } else {
      std::set<std::pair<std::string, std::string>> members;  // (class, user) checked on this server
      // A person's login sends through the server's checks alone (it refuses events of others
      // one by one); the administrator's connection first checks that the sender is a member.
      bool account = false;
      if ((*server)->backend() == Backend::Postgres) {
        auto identity = serverIdentity(**server);
        if (!identity) entry.error = identity.error();
        else account = identity->account;
      }
      while (!entry.error) {
        auto batch = pendingBatch(local, url, std::max(1, options.batchSize));
        if (!batch) return tl::unexpected(batch.error());
        if (batch->empty()) break;
        for (const PendingEvent& p : *batch) {
          if (account || !members.insert({p.classCode, p.userName}).second) continue;
          auto role = memberRole(**server, p.classCode, p.userName);
          if (!role) {
            entry.error = role.error();
            if (role.error().kind == ErrorKind::NotFound) {
              entry.error->kind = ErrorKind::Conflict;
              entry.error->message += " on " + entry.server + " (join it with `anatomy-tutor class join`)";
            }
            break;
          }
        }
        if (entry.error) break;
        const auto start = std::chrono::steady_clock::now();
        std::vector<std::pair<std::int64_t, std::string>> refusals;
        if (auto pushed = pushBatch(**server, *batch, entry, refusals); !pushed) {
          entry.error = pushed.error();
          break;
        }
        report.commitMs.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
        if (auto marked = markSent(local, url, batch->front().seq, batch->back().seq, refusals); !marked)
          return tl::unexpected(withContext("marking pushed events sent", marked.error()));
      }
    }
    if (entry.error && entry.error->kind != ErrorKind::Conflict) open.drop(url);
    auto pending = pendingFor(local, url);
    if (!pending) return tl::unexpected(pending.error());
    entry.pending = *pending;
    report.servers.push_back(std::move(entry));
  }
  return report;
}

}  // namespace at::db
