// A class server students cannot cheat: each person connects with their own PostgreSQL login, and
// every attack a student can make with it — through the program or with raw SQL on the same
// connection — is refused by the server, while the student's own answers still land.
#include <doctest/doctest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <atomic>
#include <ctime>
#include <set>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/class_accounts.h"
#include "db/class_server.h"
#include "db/course_store.h"
#include "db/sql_repositories.h"
#include "db/study_store.h"
#include "db/study_withdrawal.h"
#include "quiz/study_protocol.h"
#include "lessons/lesson_engine.h"
#include "secure_class.h"
#include "test_databases.h"
#include "test_support.h"
#include "toy_course.h"
#include "toy_play.h"
#include "uuid.h"  // db/src

namespace fs = std::filesystem;

using namespace at;
using namespace at::db;
using namespace at::lessons;

namespace {

using test::openAt;
using test::SecureClass;
using test::loginUrl;
using test::uniqueLogin;
std::int64_t count(Database& db, const std::string& sql) { return test::scalarCount(db, sql); }

// A laptop: its own SQLite file with the toy course, a local user named as the login, joined.
struct Laptop {
  Database db;
  std::int64_t userId = 0;
  SqlCurriculumRepository curriculum;
  SqlProgressRepository progress;
  test::ToyKeys keys;

  Laptop(const std::string& path, const std::string& login, const std::string& serverUrl, const std::string& code)
      : db(openAt(path)), curriculum(db, test::toyBuiltin()), progress(db) {
    REQUIRE(storeCourse(db, test::toyCourse(), "toy"));
    SqlUserRepository users(db);
    auto user = users.createUser(login, Role::Student, "");
    REQUIRE(user);
    userId = user->id;
    Database server = openAt(serverUrl);
    auto role = joinClass(server, code, login);
    REQUIRE_MESSAGE(role, (role ? "" : role.error().message));
    REQUIRE(rememberMembership(db, {login, code, serverUrl, *role}));
  }

  int play(const std::string& lessonId) {
    LessonEngine engine(curriculum, progress, keys);
    auto started = engine.start(userId, lessonId);
    REQUIRE_MESSAGE(started, (started ? "" : started.error().message));
    const int answered = test::playAnswering(engine, [](int n) { return n % 2 == 0; });
    if (engine.atEnd()) REQUIRE(engine.finish());
    return answered;
  }

  // A row written straight into the outbox, as a student editing her own database would.
  void forge(const std::string& uuid, const std::string& user, const std::string& kind, const std::string& lesson,
             const std::string& question, std::optional<int> correct, std::optional<double> score,
             std::int64_t occurredAt = std::int64_t(std::time(nullptr))) {
    auto s = db.prepare(
        "INSERT INTO outbox (uuid, server, class_code, user_name, kind, occurred_at, lesson_id, question_id, structure,"
        " correct, score) SELECT ?1, server, class_code, ?2, ?3, ?4, ?5, ?6, 'stapes', ?7, ?8 FROM class_memberships");
    REQUIRE(s);
    s->bind(1, uuid).bind(2, user).bind(3, kind).bind(4, occurredAt).bind(5, lesson).bind(6, question);
    s->bind(7, correct ? std::optional<std::int64_t>(*correct) : std::nullopt).bind(8, score);
    REQUIRE(s->run());
  }
};

SyncReport syncNow(Database& local) {
  auto report = syncOutbox(local);
  REQUIRE_MESSAGE(report, (report ? "" : report.error().message));
  return *report;
}

// A statement refused for want of rights (not for a constraint it happened to break).
bool refusedForRights(const Error& e) {
  return e.message.find("permission denied") != std::string::npos || e.message.find("must be owner") != std::string::npos;
}

// Every table of the server's schema, read by the administrator.
std::vector<std::string> serverTables(Database& admin) {
  auto s = admin.prepare("SELECT tablename FROM pg_tables WHERE schemaname = current_schema() ORDER BY tablename");
  REQUIRE(s);
  std::vector<std::string> out;
  while (*s->step()) out.push_back(s->text(0));
  REQUIRE(out.size() > 20);
  return out;
}

}  // namespace

TEST_CASE("Each person is their own login: a student can neither promote nor impersonate anyone") {
  auto url = test::freshPostgresDatabase("the class-server security test");
  if (!url) return;
  SecureClass c(*url);
  Database sam = openAt(c.samUrl);
  Database coordinator = openAt(c.coordinatorUrl);
  Database instructor = openAt(c.instructorUrl);

  auto who = serverIdentity(sam);
  REQUIRE(who);
  CHECK(who->login == c.sam);
  CHECK(who->account);
  CHECK_FALSE(serverIdentity(c.admin)->account);
  CHECK(actingName(sam, std::nullopt) == c.sam);
  auto pretend = actingName(sam, c.coordinator);
  REQUIRE_FALSE(pretend);
  CHECK((pretend.error().kind == ErrorKind::Conflict));
  CHECK(pretend.error().message.find("logged in to the class server as " + c.sam) != std::string::npos);

  // Through the program: every way a student could change roles or see the class is refused.
  CHECK_FALSE(setMemberRole(sam, c.code, c.sam, c.sam, ClassRole::Coordinator));
  auto asAda = setMemberRole(sam, c.code, c.coordinator, c.sam, ClassRole::Coordinator);
  REQUIRE_FALSE(asAda);
  CHECK(asAda.error().message.find("cannot act as " + c.coordinator) != std::string::npos);
  CHECK_FALSE(setMemberRole(sam, c.code, c.coordinator, c.coordinator, ClassRole::Student));
  CHECK_FALSE(setMemberRole(instructor, c.code, c.instructor, c.sam, ClassRole::Coordinator));
  CHECK_FALSE(createClassAccount(sam, c.code, uniqueLogin("mallory"), ClassRole::Coordinator, std::nullopt));
  CHECK_FALSE(withdrawMember(sam, c.code, c.eve, "I do not like her", std::nullopt));
  CHECK_FALSE(classProgress(sam, c.code, c.coordinator));
  auto ownView = classProgress(sam, c.code, "");
  REQUIRE_FALSE(ownView);
  CHECK(ownView.error().message.find("is a student of class") != std::string::npos);
  CHECK_FALSE(joinClass(sam, c.code, c.eve));
  CHECK_FALSE(createClass(sam, "My own class", c.sam));

  // Through raw SQL on the student's own connection.
  const std::string q = "'" + c.code + "', '" + c.sam + "', 'coordinator', '";
  for (const std::string& sql :
       {"SELECT at_set_role(" + q + c.coordinator + "')", "SELECT at_set_role(" + q + c.sam + "')",
        "SELECT at_set_role(" + q + "')",
        "SELECT at_create_account('" + c.code + "', '" + uniqueLogin("mallory") + "', 'coordinator', 'aaaaaaaaaaaaaaaaaaaa', '" + c.coordinator + "')",
        "UPDATE class_members SET role = 'coordinator' WHERE user_name = '" + c.sam + "'",
        "INSERT INTO class_members (class_code, user_name, role, joined_at) VALUES ('" + c.code + "', 'x', 'coordinator', 0)",
        std::string("SET ROLE at_class_owner"), "SET SESSION AUTHORIZATION " + c.coordinator, "ALTER ROLE " + c.sam + " CREATEROLE",
        "GRANT at_class_owner TO " + c.sam, "ALTER ROLE " + c.coordinator + " PASSWORD 'taken_over_taken_over'",
        "SELECT at_audit('" + c.sam + "', 'role', '" + c.code + "', '" + c.sam + "', 'student', 'coordinator', '')",
        std::string("CREATE FUNCTION at_is_account() RETURNS boolean LANGUAGE sql AS 'SELECT false'")}) {
    CAPTURE(sql);
    CHECK_FALSE(sam.exec(sql));
  }
  CHECK(memberRole(c.admin, c.code, c.sam) == ClassRole::Student);
  CHECK(memberRole(c.admin, c.code, c.coordinator) == ClassRole::Coordinator);
  CHECK(count(c.admin, "SELECT COUNT(*) FROM class_members WHERE role = 'coordinator'") == 1);

  // The coordinator (as herself, no --user needed) gives roles; the audit says who and what.
  REQUIRE(setMemberRole(coordinator, c.code, c.coordinator, c.eve, ClassRole::Instructor));
  CHECK(memberRole(c.admin, c.code, c.eve) == ClassRole::Instructor);
  auto audit = classAudit(coordinator, c.code);
  REQUIRE(audit);
  REQUIRE_FALSE(audit->empty());
  CHECK(audit->back().action == "role");
  CHECK(audit->back().actor == c.coordinator);
  CHECK(audit->back().login == c.coordinator);
  CHECK(audit->back().target == c.eve);
  CHECK(audit->back().oldValue == "student");
  CHECK(audit->back().newValue == "instructor");
  CHECK(classAudit(sam, c.code)->empty());  // students read no audit
}

TEST_CASE("A student login holds no write on any table: update, delete, truncate, insert and drop are refused") {
  auto url = test::freshPostgresDatabase("the class-server security test");
  if (!url) return;
  SecureClass c(*url);
  test::TempDir dir;
  Laptop eve((dir.path() / "eve.db").string(), c.eve, c.eveUrl, c.code);
  CHECK(eve.play("toy.ossicles") == 3);
  REQUIRE(syncNow(eve.db).complete());
  Database sam = openAt(c.samUrl);
  // Every table, including those changed by later migrations (study trials' nullable viewing
  // times), stays the owner role's, with row-level security on the class tables.
  CHECK(count(c.admin, "SELECT COUNT(*) FROM pg_tables WHERE schemaname = current_schema()"
                       " AND tableowner <> 'at_class_owner'") == 0);
  // Every class and study table (those a later migration adds included) has row-level security;
  // class_memberships is a laptop's own list of the classes it joined (empty on the server, and
  // written by no login: the loop below).
  CHECK(count(c.admin, "SELECT COUNT(*) FROM pg_tables WHERE schemaname = current_schema() AND NOT rowsecurity"
                       " AND (tablename LIKE 'class%' OR tablename LIKE 'stud%') AND tablename <> 'class_memberships'") == 0);
  CHECK(count(c.admin, "SELECT COUNT(*) FROM pg_tables WHERE schemaname = current_schema() AND rowsecurity") >= 14);
  CHECK(count(c.admin, "SELECT COUNT(*) FROM information_schema.columns WHERE table_schema = current_schema()"
                       " AND table_name = 'study_trials' AND column_name IN ('view_ms_a', 'view_ms_b')"
                       " AND is_nullable = 'YES'") == 2);

  for (const std::string& table : serverTables(c.admin)) {
    CAPTURE(table);
    auto column = c.admin.prepare("SELECT column_name FROM information_schema.columns WHERE table_schema = current_schema()"
                                  " AND table_name = ?1 ORDER BY ordinal_position LIMIT 1");
    REQUIRE(column);
    column->bind(1, table);
    REQUIRE(*column->step());
    const std::string first = column->text(0);
    const std::int64_t rows = count(c.admin, "SELECT COUNT(*) FROM " + table);
    for (const std::string& sql :
         {"UPDATE " + table + " SET " + first + " = " + first, "DELETE FROM " + table, "TRUNCATE " + table,
          "INSERT INTO " + table + " DEFAULT VALUES", "DROP TABLE " + table, "ALTER TABLE " + table + " DISABLE ROW LEVEL SECURITY",
          "ALTER TABLE " + table + " OWNER TO " + c.sam}) {
      CAPTURE(sql);
      auto done = sam.exec(sql);
      REQUIRE_FALSE(done);
      CHECK(refusedForRights(done.error()));
    }
    CHECK(count(c.admin, "SELECT COUNT(*) FROM " + table) == rows);
    // A GRANT by the student grants nothing (PostgreSQL only warns): the rights stay none.
    (void)sam.exec("GRANT ALL ON " + table + " TO " + c.sam);
    CHECK(count(c.admin, "SELECT COUNT(*) FROM (VALUES (1)) v WHERE has_table_privilege('" + c.sam + "', '" + table +
                             "', 'INSERT, UPDATE, DELETE, TRUNCATE, REFERENCES, TRIGGER')") == 0);
  }
  CHECK(count(c.admin, "SELECT COUNT(*) FROM class_events WHERE user_name = '" + c.eve + "'") == 5);
  CHECK(count(c.admin, "SELECT COUNT(*) FROM class_events WHERE correct = 0") == 1);
}

TEST_CASE("A student reads only her own rows: no one else's answers, no A/B keys, ratings, exam items or audit") {
  auto url = test::freshPostgresDatabase("the class-server security test");
  if (!url) return;
  SecureClass c(*url);
  test::TempDir dir;
  Laptop eve((dir.path() / "eve.db").string(), c.eve, c.eveUrl, c.code);
  Laptop sam((dir.path() / "sam.db").string(), c.sam, c.samUrl, c.code);
  CHECK(eve.play("toy.ossicles") == 3);
  CHECK(sam.play("toy.ossicles") == 3);
  REQUIRE(syncNow(eve.db).complete());
  REQUIRE(syncNow(sam.db).complete());
  Database samServer = openAt(c.samUrl);
  Database instructor = openAt(c.instructorUrl);

  // What a student may read at all: her class, her membership, her events, the class's exams (and
  // the schema version); the study tables only as their owner, so for her no row of them.
  const std::set<std::string> readable = {"at_schema_version", "classes",           "class_members",
                                          "class_events",      "class_audit",       "class_exams",
                                          "class_exam_items",  "class_exam_sittings", "class_exam_answers",
                                          "studies",           "study_participants", "study_trials",
                                          "study_ratings"};
  for (const std::string& table : serverTables(c.admin)) {
    CAPTURE(table);
    auto s = samServer.prepare("SELECT COUNT(*) FROM " + table);
    REQUIRE(s);
    auto row = s->step();
    CHECK(bool(row) == (readable.count(table) == 1));
  }
  CHECK(count(samServer, "SELECT COUNT(*) FROM class_events WHERE user_name = '" + c.sam + "'") == 5);
  CHECK(count(samServer, "SELECT COUNT(*) FROM class_events WHERE user_name <> '" + c.sam + "'") == 0);
  CHECK(count(samServer, "SELECT COUNT(*) FROM class_members WHERE user_name <> '" + c.sam + "'") == 0);
  CHECK(count(samServer, "SELECT COUNT(*) FROM class_audit") == 0);
  {  // A study with a participant and their blinded trials (the A/B keys), owned by the coordinator.
    auto survey = quiz::loadStudyProtocol((test::sourceDir() / "data/studies/paper_survey.json").string());
    REQUIRE(survey);
    REQUIRE(saveStudy(c.admin, *survey));
    REQUIRE(setStudyOwner(c.admin, survey->id, c.coordinator));
    REQUIRE(enrolOrResume(c.admin, *survey, "P0", survey->groups[0]));
  }
  for (const char* study : {"studies", "study_participants", "study_trials"}) {
    CHECK(count(samServer, std::string("SELECT COUNT(*) FROM ") + study) == 0);
    CHECK(count(instructor, std::string("SELECT COUNT(*) FROM ") + study) == 0);
    CHECK(count(c.admin, std::string("SELECT COUNT(*) FROM ") + study) > 0);
  }
  CHECK(count(c.admin, "SELECT COUNT(*) FROM class_events WHERE user_name = '" + c.eve + "'") == 5);
  // The instructor sees the class: both students' events.
  CHECK(count(instructor, "SELECT COUNT(*) FROM class_events") == 10);
  auto progress = classProgress(instructor, c.code, "");
  REQUIRE_MESSAGE(progress, (progress ? "" : progress.error().message));
  CHECK(progress->students.size() == 2);
}

TEST_CASE("The server decides what counts: forged outbox events are refused with their reason, real answers land") {
  auto url = test::freshPostgresDatabase("the class-server security test");
  if (!url) return;
  SecureClass c(*url);
  test::TempDir dir;
  Laptop eve((dir.path() / "eve.db").string(), c.eve, c.eveUrl, c.code);
  Laptop sam((dir.path() / "sam.db").string(), c.sam, c.samUrl, c.code);
  CHECK(eve.play("toy.ossicles") == 3);
  REQUIRE(syncNow(eve.db).complete());
  Database instructor = openAt(c.instructorUrl);
  auto before = classProgress(instructor, c.code, "");
  REQUIRE(before);
  const auto eveBefore = before->students[0].userName == c.eve ? before->students[0] : before->students[1];
  REQUIRE(eveBefore.userName == c.eve);
  std::string eveUuid;
  {
    auto s = c.admin.prepare("SELECT uuid FROM class_events WHERE user_name = ?1 LIMIT 1");
    REQUIRE(s);
    s->bind(1, c.eve);
    REQUIRE(*s->step());
    eveUuid = s->text(0);
  }

  // Forgeries written straight into sam's outbox, of every kind, in a random mix (seed printed).
  const std::uint64_t seed = test::freshSeed("ClassSecurity_ForgedOutboxEvents");
  INFO("forgery seed " << seed);
  std::mt19937 random{unsigned(seed)};
  const std::int64_t now = std::int64_t(std::time(nullptr));
  int forged = 0;
  auto forgeOne = [&](int kind) {
    ++forged;
    switch (kind) {
      case 0: sam.forge(newUuid(), c.eve, "answer", "toy.ossicles", "toy.ossicles.name_stapes", 0, 0.0); break;  // as eve
      case 1: sam.forge(newUuid(), c.sam, "answer", "toy.ossicles", "toy.ossicles.invented_" + std::to_string(random()), 1, 1.0); break;
      case 2: sam.forge(newUuid(), c.sam, "lesson_started", "toy.middle", "", std::nullopt, std::nullopt); break;  // locked
      case 3: sam.forge(newUuid(), c.sam, "lesson_finished", "toy.middle", "", std::nullopt, 1.0); break;  // locked, never started
      case 4: sam.forge("not-a-uuid-" + std::to_string(random()), c.sam, "answer", "toy.ossicles", "toy.ossicles.name_stapes", 1, 1.0); break;
      case 5: sam.forge(newUuid(), c.sam, "answer", "toy.ossicles", "toy.ossicles.name_stapes", 2, 7.0); break;  // grade
      case 6: sam.forge(eveUuid, c.sam, "answer", "toy.ossicles", "toy.ossicles.name_stapes", 1, 1.0); break;  // eve's id
      case 7: sam.forge(newUuid(), c.sam, "answer", "toy.ossicles", "toy.ossicles.name_stapes", 1, 1.0, now + 30 * 86400); break;
      case 8: sam.forge(newUuid(), c.sam, "answer", "", "toy.middle.none", 1, 1.0); break;
      default: sam.forge(newUuid(), c.sam, "promoted", "toy.ossicles", "", std::nullopt, std::nullopt); break;
    }
  };
  for (int kind = 0; kind < 10; ++kind) forgeOne(kind);  // each kind at least once
  std::uniform_int_distribution<int> anyKind(0, 9);
  for (int i = 0; i < 10; ++i) {
    const int kind = anyKind(random);
    forgeOne(kind == 6 ? 7 : kind);  // eve's id once: the laptop's outbox keeps ids unique itself
  }
  // sam's own lesson, played honestly after the forgeries: before it, toy.ossicles was not started.
  CHECK(sam.play("toy.ossicles") == 3);
  // An answer without an answer in a lesson sam has started: before her lesson such a forgery is
  // refused as "never started", so the reason checked below needs one forged after it.
  forgeOne(5);
  for (int i = 0; i < 5; ++i) forgeOne(std::array{0, 1, 3, 4, 5}[std::size_t(anyKind(random) % 5)]);

  auto report = syncNow(sam.db);
  REQUIRE(report.servers.size() == 1);
  const ServerSync& r = report.servers[0];
  CHECK(r.pushed == 5);  // start, three answers, finish
  CHECK(r.refused == forged);
  CHECK(r.pending == 0);
  REQUIRE_FALSE(r.refusals.empty());
  for (const std::string& why : r.refusals) CHECK(why.find("refused") == std::string::npos);  // the reason, without the prefix
  CHECK(count(sam.db, "SELECT COUNT(*) FROM outbox WHERE refused IS NOT NULL") == forged);
  CHECK(count(sam.db, "SELECT COUNT(*) FROM outbox WHERE refused LIKE '%but was sent by the login " + c.sam + "%'") > 0);
  CHECK(count(sam.db, "SELECT COUNT(*) FROM outbox WHERE refused LIKE '%no question toy.ossicles.invented_%'") > 0);
  CHECK(count(sam.db, "SELECT COUNT(*) FROM outbox WHERE refused LIKE '%lesson toy.middle is locked for " + c.sam + "%'") > 0);
  CHECK(count(sam.db, "SELECT COUNT(*) FROM outbox WHERE refused LIKE '%is not a UUID%'") > 0);
  // A forged answer carries no answer to grade (the server grades what was answered, not the grade sent).
  CHECK(count(sam.db, "SELECT COUNT(*) FROM outbox WHERE refused LIKE '%it carries no answer%'") > 0);
  CHECK(count(sam.db, "SELECT COUNT(*) FROM outbox WHERE refused LIKE '%is already used%'") > 0);
  CHECK(count(sam.db, "SELECT COUNT(*) FROM outbox WHERE refused LIKE '%impossible time%'") > 0);
  CHECK(count(sam.db, "SELECT COUNT(*) FROM outbox WHERE refused LIKE '%not answer, lesson_started or lesson_finished%'") > 0);
  CHECK(outboxCounts(sam.db)->refused == forged);
  auto again = syncNow(sam.db);  // refused events are not sent again
  CHECK(again.servers.empty());

  // What the server holds: sam's honest lesson, exactly, and eve unchanged.
  CHECK(count(c.admin, "SELECT COUNT(*) FROM class_events WHERE user_name = '" + c.sam + "'") == 5);
  CHECK(count(c.admin, "SELECT COUNT(*) FROM class_events") == 10);
  auto after = classProgress(instructor, c.code, "");
  REQUIRE(after);
  for (const auto& s : after->students) {
    if (s.userName != c.eve) continue;
    CHECK(s.answers == eveBefore.answers);
    CHECK(s.correct == eveBefore.correct);
  }

  // The same forgeries by raw SQL on sam's connection: refused by the function, or no right at all.
  Database samServer = openAt(c.samUrl);
  auto record = samServer.prepare("SELECT at_record_event(?1, ?2, ?3, 'answer', ?4, 'toy.ossicles', 'toy.ossicles.name_stapes',"
                                  " 'stapes', 0, 0.0, '{}')");
  REQUIRE(record);
  record->bind(1, newUuid()).bind(2, c.code).bind(3, c.eve).bind(4, now);
  REQUIRE(*record->step());
  CHECK(record->text(0).rfind("refused: ", 0) == 0);
  auto insert = samServer.exec("INSERT INTO class_events (uuid, class_code, user_name, kind, occurred_at, received_at) VALUES ('" +
                               newUuid() + "', '" + c.code + "', '" + c.eve + "', 'answer', 0, 0)");
  REQUIRE_FALSE(insert);
  CHECK(refusedForRights(insert.error()));
  CHECK(count(c.admin, "SELECT COUNT(*) FROM class_events") == 10);
}

TEST_CASE("Corrections and withdrawals go through audited functions; the audit cannot be changed") {
  auto url = test::freshPostgresDatabase("the class-server security test");
  if (!url) return;
  SecureClass c(*url);
  test::TempDir dir;
  Laptop sam((dir.path() / "sam.db").string(), c.sam, c.samUrl, c.code);
  CHECK(sam.play("toy.ossicles") == 3);  // right, wrong, right
  REQUIRE(syncNow(sam.db).complete());
  Database coordinator = openAt(c.coordinatorUrl);
  Database samServer = openAt(c.samUrl);
  std::string wrongAnswer;
  {
    auto s = c.admin.prepare("SELECT uuid FROM class_events WHERE kind = 'answer' AND correct = 0");
    REQUIRE(s);
    REQUIRE(*s->step());
    wrongAnswer = s->text(0);
  }
  // The student cannot correct herself, with the program or with SQL.
  CHECK_FALSE(correctClassEvent(samServer, wrongAnswer, true, 1.0, "I was right", std::nullopt));
  CHECK_FALSE(samServer.exec("SELECT at_correct_event('" + wrongAnswer + "', 1, 1.0, 'I was right', '')"));
  // Right: the name; her right locate pick (made on the laptop's view, no pixel) is practice.
  CHECK(count(c.admin, "SELECT COUNT(*) FROM class_events WHERE correct = 1") == 1);
  CHECK(count(c.admin, "SELECT COUNT(*) FROM class_events WHERE practice = 1") == 1);

  const std::int64_t audited = count(c.admin, "SELECT COUNT(*) FROM class_audit");
  REQUIRE(correctClassEvent(coordinator, wrongAnswer, true, 1.0, "synonym 'stirrup' accepted", std::nullopt));
  CHECK(count(c.admin, "SELECT COUNT(*) FROM class_events WHERE correct = 1") == 2);
  auto audit = classAudit(coordinator, c.code);
  REQUIRE(audit);
  // Its own row, then the row of the lesson end it changed (her ossicles lesson: 0.5 → 1).
  REQUIRE(std::int64_t(audit->size()) == audited + 2);
  const ClassAuditEntry& e = (*audit)[std::size_t(audited)];
  CHECK(e.action == "correct");
  CHECK(e.actor == c.coordinator);
  CHECK(e.login == c.coordinator);
  CHECK(e.target == c.sam + " " + wrongAnswer);
  CHECK(e.oldValue->find("\"correct\" : 0") != std::string::npos);
  CHECK(e.newValue->find("\"correct\" : 1") != std::string::npos);
  CHECK(e.reason == "synonym 'stirrup' accepted");
  CHECK(e.recordedAt.size() >= 20);
  const ClassAuditEntry& end = audit->back();
  CHECK(end.action == "lesson_score");
  CHECK(end.login == c.coordinator);
  CHECK(end.target.rfind(c.sam + " ", 0) == 0);
  CHECK(end.oldValue == std::optional<std::string>("{\"score\" : 0.5}"));
  CHECK(end.newValue == std::optional<std::string>("{\"score\" : 1}"));
  CHECK(end.reason.find(wrongAnswer) != std::string::npos);

  // Withdrawal: kept with its reason; the member's later events no longer count.
  REQUIRE(withdrawMember(coordinator, c.code, c.sam, "consent withdrawn by e-mail", std::nullopt));
  auto progress = classProgress(coordinator, c.code, "");
  REQUIRE(progress);
  bool seen = false;
  for (const auto& s : progress->students)
    if (s.userName == c.sam) {
      seen = true;
      CHECK(s.withdrawal == "consent withdrawn by e-mail");
    }
  CHECK(seen);
  CHECK(classAudit(coordinator, c.code)->back().action == "withdraw");
  CHECK(sam.play("toy.middle") == 3);
  auto late = syncNow(sam.db);
  CHECK(late.servers[0].pushed == 0);
  CHECK(late.servers[0].refused == 5);

  // Nobody changes the audit: not the student (no right), not even the administrator (append-only).
  CHECK_FALSE(samServer.exec("DELETE FROM class_audit"));
  for (const char* sql : {"UPDATE class_audit SET reason = ''", "DELETE FROM class_audit", "TRUNCATE class_audit"}) {
    CAPTURE(sql);
    auto done = c.admin.exec(sql);
    REQUIRE_FALSE(done);
    CHECK(done.error().message.find("append-only") != std::string::npos);
  }
  CHECK(count(c.admin, "SELECT COUNT(*) FROM class_audit") == audited + 3);  // correction, lesson end, withdrawal
}

TEST_CASE("Accounts: a password is shown once, existing logins keep theirs, other roles cannot be taken over") {
  auto url = test::freshPostgresDatabase("the class-server security test");
  if (!url) return;
  SecureClass c(*url);
  Database coordinator = openAt(c.coordinatorUrl);
  auto again = createClassAccount(coordinator, c.code, c.sam, ClassRole::Student, std::nullopt);
  REQUIRE(again);
  CHECK_FALSE(again->password);
  openAt(c.samUrl);  // the first password still works
  auto admin = serverIdentity(c.admin);
  REQUIRE(admin);
  for (const std::string& name : {admin->login, std::string("at_class_owner"), std::string("pg_monitor"),
                                  std::string("Robert'); DROP TABLE classes; --"), std::string("x")}) {
    CAPTURE(name);
    auto taken = createClassAccount(coordinator, c.code, name, ClassRole::Coordinator, std::nullopt);
    CHECK_FALSE(taken);
  }
  CHECK(count(c.admin, "SELECT COUNT(*) FROM classes") == 1);
  CHECK_FALSE(createClassAccount(c.admin, "ZZZZZZZZ", uniqueLogin("zed"), ClassRole::Student, std::nullopt));
}

namespace {

// The text after `marker` up to the end of its line.
std::string after(const std::string& text, const std::string& marker) {
  const auto at = text.find(marker);
  if (at == std::string::npos) return "";
  const auto from = at + marker.size();
  return text.substr(from, text.find('\n', from) - from);
}

}  // namespace

TEST_CASE("Through the command line: accounts print a password once or write a pgpass line; --user never impersonates") {
  if (!test::requireAppBinary("the class-server CLI security test")) return;
  auto url = test::freshPostgresDatabase("the class-server CLI security test");
  if (!url) return;
  test::TempDir dir;
  const std::string ada = uniqueLogin("ada"), sam = uniqueLogin("sam"), eve = uniqueLogin("eve");
  auto made = test::runApp("class create 'Ear anatomy' --user " + ada + " --db '" + *url + "'");
  CAPTURE(made.err);
  REQUIRE(made.exitCode == 0);
  const std::string code = after(made.out, "code ").substr(0, 8);
  REQUIRE(normalizeClassCode(code) == code);

  auto adaAccount = test::runApp("class account " + code + " " + ada + " --role coordinator --db '" + *url + "'");
  CAPTURE(adaAccount.err);
  REQUIRE(adaAccount.exitCode == 0);
  const std::string adaPassword = after(adaAccount.out, "password (shown once, not stored; hand it to " + ada + "): ");
  REQUIRE(adaPassword.size() == 24);
  const std::string adaUrl = loginUrl(*url, ada, adaPassword);

  const fs::path pgpass = dir.path() / "sam.pgpass";
  auto samAccount = test::runApp("class account " + code + " " + sam + " --role student --db '" + adaUrl + "' --pgpass '" +
                                 pgpass.string() + "'");
  CAPTURE(samAccount.err);
  REQUIRE(samAccount.exitCode == 0);
  CHECK(samAccount.out.find("password (shown once") == std::string::npos);  // only in the file
  CHECK((fs::status(pgpass).permissions() & fs::perms::group_all) == fs::perms::none);
  CHECK((fs::status(pgpass).permissions() & fs::perms::others_all) == fs::perms::none);
  const std::string line = test::readFile(pgpass);
  CHECK(line.find(":" + sam + ":") != std::string::npos);
  const std::string samPassword = line.substr(line.rfind(':') + 1, 24);
  const std::string samUrl = loginUrl(*url, sam, samPassword);
  REQUIRE(test::runApp("class account " + code + " " + eve + " --role student --db '" + adaUrl + "'").exitCode == 0);
  auto twice = test::runApp("class account " + code + " " + sam + " --role student --db '" + adaUrl + "'");
  CHECK(twice.exitCode == 0);
  CHECK(twice.out.find("existed already and keeps its password") != std::string::npos);

  // sam, as himself: no promotion, no impersonation, no class view; each refusal is one line.
  for (const std::string& args :
       {"class role " + code + " " + sam + " coordinator --user " + ada, "class role " + code + " " + sam + " coordinator",
        "class role " + code + " " + ada + " student", "class progress " + code, "class progress " + code + " --user " + ada,
        "class account " + code + " " + uniqueLogin("mallory") + " --role coordinator",
        "class withdraw " + code + " " + eve + " --reason spite"}) {
    CAPTURE(args);
    auto refused = test::runApp(args + " --db '" + samUrl + "'");
    CHECK(refused.exitCode == 1);
    CHECK(std::count(refused.err.begin(), refused.err.end(), '\n') == 1);
  }
  CHECK(test::runApp("class role " + code + " " + sam + " coordinator --user " + ada + " --db '" + samUrl + "'")
            .err.find("you are logged in to the class server as " + sam) != std::string::npos);

  // sam's laptop: joins as himself; a forged event under eve's name is refused, with the reason shown.
  const std::string local = (dir.path() / "laptop.db").string();
  auto joined = test::runApp("class join " + code + " --server '" + samUrl + "' --db '" + local + "'");
  CAPTURE(joined.err);
  REQUIRE(joined.exitCode == 0);
  CHECK(joined.out.find(sam + " joined class " + code) != std::string::npos);
  {
    Database laptop = openAt(local);
    auto s = laptop.prepare(
        "INSERT INTO outbox (uuid, server, class_code, user_name, kind, occurred_at, lesson_id, question_id, correct, score)"
        " SELECT ?1, server, class_code, ?2, 'lesson_started', ?3, 'inner_ear', '', NULL, NULL FROM class_memberships");
    REQUIRE(s);
    s->bind(1, newUuid()).bind(2, eve).bind(3, std::int64_t(std::time(nullptr)));
    REQUIRE(s->run());
  }
  auto sync = test::runApp("sync --db '" + local + "'");
  CHECK(sync.exitCode == 1);
  CHECK(sync.err.find("1 event refused: event ") != std::string::npos);
  CHECK(sync.err.find("names " + eve + " but was sent by the login " + sam) != std::string::npos);

  auto audit = test::runApp("class audit " + code + " --db '" + adaUrl + "'");
  CAPTURE(audit.err);
  REQUIRE(audit.exitCode == 0);
  CHECK(audit.out.find("," + ada + "," + ada + ",account," + sam + ",") != std::string::npos);
}
