// Classes on a class server (codes, roles, the instructor's view) and the offline-first outbox:
// learners' machines keep their SQLite files, their events reach a real PostgreSQL server once,
// whatever happens to the server in between.
#include <doctest/doctest.h>

#include <filesystem>
#include <set>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/class_server.h"
#include "db/course_store.h"
#include "db/sql_repositories.h"
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
std::int64_t count(Database& db, const std::string& sql) { return test::scalarCount(db, sql); }

// A learner's machine: its own SQLite file with the toy course and the user `name`.
struct LearnerMachine {
  Database db;
  std::int64_t userId = 0;
  SqlCurriculumRepository curriculum;
  SqlProgressRepository progress;
  test::ToyKeys keys;

  LearnerMachine(const std::string& path, const std::string& name)
      : db(openAt(path)), curriculum(db, test::toyBuiltin()), progress(db) {
    REQUIRE(storeCourse(db, test::toyCourse(), "toy"));
    SqlUserRepository users(db);
    auto user = users.createUser(name, Role::Student, "");
    REQUIRE(user);
    userId = user->id;
  }

  // Plays `lessonId` from where it stands; answers alternate right and wrong from the first.
  int play(const std::string& lessonId, int stopAfter = 1 << 30, bool finish = true) {
    LessonEngine engine(curriculum, progress, keys);
    auto started = engine.start(userId, lessonId);
    REQUIRE_MESSAGE(started, (started ? "" : started.error().message));
    const int answered = test::playAnswering(engine, [](int n) { return n % 2 == 0; }, stopAfter);
    if (finish && engine.atEnd()) REQUIRE(engine.finish());
    return answered;
  }
};

// A class "Ear anatomy" coordinated by dr_ada, on a server that has the toy course (it judges
// the events against it) and its answer keys (it grades the answers with them).
ClassInfo newClass(Database& server) {
  REQUIRE(storeCourse(server, test::toyCourse(), "toy"));
  auto made = createClass(server, "Ear anatomy", "dr_ada");
  REQUIRE_MESSAGE(made, (made ? "" : made.error().message));
  if (server.backend() == Backend::Postgres) {
    auto published = publishLessonKeys(server, made->code, test::toyLessonKeys(), "dr_ada");
    REQUIRE_MESSAGE(published, (published ? "" : published.error().message));
  }
  return *made;
}

SyncReport syncNow(Database& local) {
  auto report = syncOutbox(local);
  REQUIRE_MESSAGE(report, (report ? "" : report.error().message));
  return *report;
}

}  // namespace

TEST_CASE("Event UUIDs are random version-4 UUIDs, never the same twice") {
  std::set<std::string> seen;
  for (int i = 0; i < 20000; ++i) {
    const std::string u = newUuid();
    REQUIRE(isUuid(u));
    CHECK(u[14] == '4');
    CHECK(std::string("89ab").find(u[19]) != std::string::npos);
    seen.insert(u);
  }
  CHECK(seen.size() == 20000);
  CHECK_FALSE(isUuid("not-a-uuid"));
  CHECK_FALSE(isUuid("123e4567-e89b-12d3-a456-42661417400G"));
}

TEST_CASE("Class codes are 8 letters and digits, typed in any case and with dashes") {
  CHECK(normalizeClassCode("k7m2-p9qx") == "K7M2P9QX");
  CHECK(normalizeClassCode("K7M2 P9QX") == "K7M2P9QX");
  for (const char* bad : {"", "K7M2P9Q", "K7M2P9QXY", "K7M2P9Q0", "K7M2P9Q!"}) {
    auto code = normalizeClassCode(bad);
    REQUIRE_FALSE(code);
    CHECK(code.error().message.find("class code '" + std::string(bad) + "'") != std::string::npos);
  }
  CHECK(parseClassRole("instructor") == ClassRole::Instructor);
  auto role = parseClassRole("teacher");
  REQUIRE_FALSE(role);
  CHECK(role.error().message == "role 'teacher' is not one of student, instructor, coordinator");
}

TEST_CASE("A class is joined with its code; coordinators give roles; only instructors and coordinators see progress") {
  test::TempDir dir;
  Database server = openAt(test::freshDatabase(dir, "server.db"));
  auto made = createClass(server, "Anatomy 1, 2026", "dr_ada");
  REQUIRE_MESSAGE(made, (made ? "" : made.error().message));
  CHECK(normalizeClassCode(made->code) == made->code);
  auto other = createClass(server, "Anatomy 2", "dr_ada");
  REQUIRE(other);
  CHECK(other->code != made->code);
  CHECK(memberRole(server, made->code, "dr_ada") == ClassRole::Coordinator);

  CHECK(joinClass(server, made->code, "sam") == ClassRole::Student);
  CHECK(joinClass(server, made->code, "sam") == ClassRole::Student);  // again: nothing changes
  CHECK(count(server, "SELECT COUNT(*) FROM class_members WHERE user_name = 'sam'") == 1);
  auto wrong = joinClass(server, "ZZZZZZZZ", "sam");
  REQUIRE_FALSE(wrong);
  CHECK((wrong.error().kind == ErrorKind::NotFound));
  CHECK(wrong.error().message.find("no class has the code ZZZZZZZZ") != std::string::npos);

  // A student can neither give roles nor see the class.
  auto byStudent = setMemberRole(server, made->code, "sam", "sam", ClassRole::Instructor);
  REQUIRE_FALSE(byStudent);
  CHECK((byStudent.error().kind == ErrorKind::Conflict));
  CHECK(memberRole(server, made->code, "sam") == ClassRole::Student);
  auto seen = classProgress(server, made->code, "sam");
  REQUIRE_FALSE(seen);
  CHECK((seen.error().kind == ErrorKind::Conflict));
  CHECK(seen.error().message.find("'sam' is a student of class " + made->code) != std::string::npos);
  auto stranger = classProgress(server, made->code, "eve");
  REQUIRE_FALSE(stranger);
  CHECK((stranger.error().kind == ErrorKind::NotFound));

  // The coordinator makes an instructor, who sees every student (none has done anything yet).
  REQUIRE(setMemberRole(server, made->code, "dr_ada", "mr_lee", ClassRole::Instructor));
  REQUIRE(joinClass(server, made->code, "kim"));
  CHECK(joinClass(server, made->code, "mr_lee") == ClassRole::Instructor);  // joining keeps the role given
  auto progress = classProgress(server, made->code, "mr_lee");
  REQUIRE_MESSAGE(progress, (progress ? "" : progress.error().message));
  CHECK(progress->info.title == "Anatomy 1, 2026");
  REQUIRE(progress->students.size() == 2);
  CHECK(progress->students[0].userName == "kim");
  CHECK(progress->students[1].userName == "sam");
  CHECK(progress->students[1].answers == 0);
  CHECK_FALSE(progress->students[1].lastActive);
  CHECK(progress->events == 0);
}

TEST_CASE("A user in no class writes nothing into the outbox") {
  test::TempDir dir;
  LearnerMachine machine((dir.path() / "local.db").string(), "solo");
  CHECK(machine.play("toy.ossicles") == 3);
  CHECK(count(machine.db, "SELECT COUNT(*) FROM outbox") == 0);
  auto report = syncNow(machine.db);
  CHECK(report.servers.empty());
  CHECK(report.complete());
}

TEST_CASE("Offline first: answers made while the class server is down reach it once when it is back") {
  test::PrivatePostgres classServer;  // stopped below: a cluster of its own, not the shared one
  auto url = classServer.freshDatabase("the class-server sync test");
  if (!url) return;
  test::TempDir dir;
  Database server = openAt(*url);
  const std::string code = newClass(server).code;

  LearnerMachine sam((dir.path() / "sam.db").string(), "sam");
  REQUIRE(joinClass(server, code, "sam"));
  REQUIRE(rememberMembership(sam.db, {"sam", code, *url, ClassRole::Student}));

  // Online: the first lesson's two answers (and its start) are pushed.
  CHECK(sam.play("toy.ossicles", 2, false) == 2);
  CHECK(count(sam.db, "SELECT COUNT(*) FROM outbox") == 3);
  auto first = syncNow(sam.db);
  REQUIRE(first.servers.size() == 1);
  CHECK(first.servers[0].pushed == 3);
  CHECK(first.complete());
  CHECK(first.servers[0].server.find(':' + std::string("@")) == std::string::npos);

  // The server goes down: learning goes on on the laptop, every event waits in the outbox.
  REQUIRE(classServer.stop());
  CHECK(sam.play("toy.ossicles") == 1);  // the last answer, then the lesson's end
  CHECK(sam.play("toy.middle") == 3);
  auto down = syncOutbox(sam.db);
  const bool restarted = classServer.restart();
  REQUIRE(restarted);
  REQUIRE_MESSAGE(down, (down ? "" : down.error().message));
  REQUIRE(down->servers.size() == 1);
  REQUIRE(down->servers[0].error);
  CHECK((down->servers[0].error->kind == ErrorKind::Unavailable));
  CHECK(down->servers[0].error->message.find('\n') == std::string::npos);
  CHECK(down->servers[0].pending == 1 + 1 + 1 + 3 + 1);  // answer, finish; start, 3 answers, finish
  CHECK_FALSE(down->complete());
  CHECK(count(sam.db, "SELECT COUNT(*) FROM responses") == 6);

  // Back: everything arrives, once.
  auto back = syncNow(sam.db);
  CHECK(back.complete());
  CHECK(back.servers[0].pushed == 7);
  const std::int64_t sent = count(sam.db, "SELECT COUNT(*) FROM outbox");
  CHECK(sent == 10);
  Database reconnected = openAt(*url);
  CHECK(count(reconnected, "SELECT COUNT(*) FROM class_events") == sent);
  CHECK(count(reconnected, "SELECT COUNT(DISTINCT uuid) FROM class_events") == sent);

  // A push the server committed but whose answer the laptop never got (the connection dropped at
  // COMMIT): the laptop pushes again; the server keeps one copy.
  REQUIRE(sam.db.exec("UPDATE outbox SET sent_at = NULL"));
  auto again = syncNow(sam.db);
  CHECK(again.complete());
  CHECK(again.servers[0].pushed == 0);
  CHECK(again.servers[0].repeated == sent);
  CHECK(count(reconnected, "SELECT COUNT(*) FROM class_events") == sent);

  // The instructor's view, computed from the events, agrees with the laptop.
  REQUIRE(joinClass(reconnected, code, "kim"));
  auto progress = classProgress(reconnected, code, "dr_ada");
  REQUIRE_MESSAGE(progress, (progress ? "" : progress.error().message));
  REQUIRE(progress->students.size() == 2);
  const StudentClassProgress& p = progress->students[1];
  CHECK(p.userName == "sam");
  // Her locate picks were made on the laptop's view, not as a pixel on the question's picture: the
  // server keeps them as practice, apart from her answers.
  const std::string locate = "SELECT COUNT(*) FROM responses r JOIN questions q ON q.id = r.question_id WHERE q.kind = 'locate'";
  const std::int64_t practice = count(sam.db, locate), practiceRight = count(sam.db, locate + " AND r.correct = 1");
  CHECK(practice > 0);
  CHECK(p.practice == practice);
  CHECK(p.answers == count(sam.db, "SELECT COUNT(*) FROM responses") - practice);
  CHECK(p.correct == count(sam.db, "SELECT COUNT(*) FROM responses WHERE correct = 1") - practiceRight);
  CHECK(p.correct == 4 - practiceRight);  // right, wrong, right in each lesson
  CHECK(p.lessonsStarted == 2);
  CHECK(p.lessonsFinished == 2);
  CHECK(p.lastActive);
  CHECK(progress->students[0].answers == 0);
  CHECK(progress->events == sent);
  int structureAnswers = 0;
  for (const auto& s : progress->structures) structureAnswers += s.answers;
  CHECK(structureAnswers == 6 - practice);
}

TEST_CASE("Two copies of one laptop's database (a restored backup) push the same events once") {
  test::PrivatePostgres classServer;  // stopped below: a cluster of its own, not the shared one
  auto url = classServer.freshDatabase("the class-server sync test");
  if (!url) return;
  test::TempDir dir;
  Database server = openAt(*url);
  const auto made = newClass(server);
  REQUIRE(joinClass(server, made.code, "sam"));
  const fs::path original = dir.path() / "sam.db";
  {
    LearnerMachine sam(original.string(), "sam");
    REQUIRE(rememberMembership(sam.db, {"sam", made.code, *url, ClassRole::Student}));
    CHECK(sam.play("toy.ossicles") == 3);
  }
  fs::copy_file(original, dir.path() / "backup.db");
  Database a = openAt(original.string());
  Database b = openAt((dir.path() / "backup.db").string());
  CHECK(syncNow(a).servers[0].pushed == 5);
  auto fromBackup = syncNow(b);
  CHECK(fromBackup.servers[0].pushed == 0);
  CHECK(fromBackup.servers[0].repeated == 5);
  CHECK(count(server, "SELECT COUNT(*) FROM class_events") == 5);
}

TEST_CASE("Events of a user the server does not know as a member stay in the outbox, with the reason") {
  test::PrivatePostgres classServer;  // stopped below: a cluster of its own, not the shared one
  auto url = classServer.freshDatabase("the class-server sync test");
  if (!url) return;
  test::TempDir dir;
  Database server = openAt(*url);
  const auto made = newClass(server);
  LearnerMachine sam((dir.path() / "sam.db").string(), "sam");
  // Joined on this laptop only (the server never heard of it).
  REQUIRE(rememberMembership(sam.db, {"sam", made.code, *url, ClassRole::Student}));
  CHECK(sam.play("toy.ossicles", 1, false) == 1);
  auto report = syncNow(sam.db);
  REQUIRE(report.servers.size() == 1);
  REQUIRE(report.servers[0].error);
  CHECK((report.servers[0].error->kind == ErrorKind::Conflict));
  CHECK(report.servers[0].error->message.find("'sam' is not a member of class " + made.code) != std::string::npos);
  CHECK(report.servers[0].pending == 2);
  CHECK(count(server, "SELECT COUNT(*) FROM class_events") == 0);
  // Joined properly, the same events go.
  REQUIRE(joinClass(server, made.code, "sam"));
  CHECK(syncNow(sam.db).servers[0].pushed == 2);
}
