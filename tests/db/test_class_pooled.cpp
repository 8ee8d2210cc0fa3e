// A class server behind PgBouncer: every person's own login (made by createClassAccount) gets
// through the pooler, whose auth_query looks its password up, and the server still sees the
// person (session_user), so its SECURITY DEFINER functions and row-level security hold there too.
#include <doctest/doctest.h>

#include <ctime>
#include <string>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/class_accounts.h"
#include "db/class_server.h"
#include "db/course_store.h"
#include "db/sql_repositories.h"
#include "lessons/lesson_engine.h"
#include "pooled_postgres.h"
#include "test_databases.h"
#include "test_support.h"
#include "toy_course.h"
#include "toy_play.h"
#include "uuid.h"  // db/src

using namespace at;
using namespace at::db;
using namespace at::lessons;

namespace {

using test::openAt;
std::int64_t count(Database& db, const std::string& sql) { return test::scalarCount(db, sql); }

// `url` with `login` and `password` in place of its user and password.
std::string loginUrl(const std::string& url, const std::string& login, const std::string& password) {
  const auto scheme = url.find("://") + 3;
  const auto at = url.find('@', scheme);
  REQUIRE(at != std::string::npos);
  return url.substr(0, scheme) + login + ":" + password + url.substr(at);
}

}  // namespace

TEST_CASE("ClassPooled_PersonLoginsThroughPgBouncer_SendAsThemselvesOthersRefused") {
  if (test::testingOnPostgres()) return;  // runs its own server: once is enough
  test::PooledPostgres server(20, 10);
  auto urls = test::pooledDatabase(server, "the pooled class-login test");
  if (!urls) return;
  const std::string suffix = std::to_string(std::time(nullptr) % 100000);
  const std::string coordinator = "pool_ada" + suffix, eve = "pool_eve" + suffix, sam = "pool_sam" + suffix;

  Database admin = openAt(urls->pooled);  // migrates through the pooler, security included
  REQUIRE(storeCourse(admin, test::toyCourse(), "toy"));
  auto made = createClass(admin, "Pooled ear anatomy", coordinator);
  REQUIRE_MESSAGE(made, (made ? "" : made.error().message));
  auto account = [&](Database& by, const std::string& name, ClassRole role) {
    auto a = createClassAccount(by, made->code, name, role, std::nullopt);
    REQUIRE_MESSAGE(a, (a ? "" : a.error().message));
    REQUIRE(a->password);
    return loginUrl(urls->pooled, name, *a->password);
  };
  const std::string coordinatorUrl = account(admin, coordinator, ClassRole::Coordinator);
  Database coordinatorDb = openAt(coordinatorUrl);  // a person's login, through the pooler
  CHECK(count(coordinatorDb, "SELECT COUNT(*) FROM (VALUES (1)) v WHERE session_user = '" + coordinator + "'") == 1);
  const std::string eveUrl = account(coordinatorDb, eve, ClassRole::Student);
  account(coordinatorDb, sam, ClassRole::Student);

  // A wrong password is turned away by the pooler.
  auto wrong = Database::open(loginUrl(urls->pooled, eve, "not-her-password-0123"));
  CHECK_FALSE(wrong);

  // Eve's laptop plays a lesson and syncs through the pooler as herself.
  test::TempDir dir;
  Database laptop = openAt((dir.path() / "eve.db").string());
  REQUIRE(storeCourse(laptop, test::toyCourse(), "toy"));
  SqlUserRepository users(laptop);
  auto user = users.createUser(eve, Role::Student, "");
  REQUIRE(user);
  {
    Database eveServer = openAt(eveUrl);
    auto role = joinClass(eveServer, made->code, eve);
    REQUIRE_MESSAGE(role, (role ? "" : role.error().message));
    REQUIRE(rememberMembership(laptop, {eve, made->code, eveUrl, *role}));
  }
  SqlCurriculumRepository curriculum(laptop, test::toyBuiltin());
  SqlProgressRepository progress(laptop);
  test::ToyKeys keys;
  LessonEngine engine(curriculum, progress, keys);
  REQUIRE(engine.start(user->id, "toy.ossicles"));
  CHECK(test::playAnswering(engine, [](int n) { return n % 2 == 0; }) == 3);
  if (engine.atEnd()) REQUIRE(engine.finish());
  // An answer in sam's name written into eve's own outbox: the server refuses it.
  {
    auto s = laptop.prepare(
        "INSERT INTO outbox (uuid, server, class_code, user_name, kind, occurred_at, lesson_id, question_id, structure,"
        " correct, score) SELECT ?1, server, class_code, ?2, 'answer', ?3, 'toy.ossicles',"
        " 'toy.ossicles.name_stapes', 'stapes', 1, 1.0 FROM class_memberships");
    REQUIRE(s);
    s->bind(1, newUuid()).bind(2, sam).bind(3, std::int64_t(std::time(nullptr)));
    REQUIRE(s->run());
  }
  auto report = syncOutbox(laptop);
  REQUIRE_MESSAGE(report, (report ? "" : report.error().message));
  REQUIRE(report->servers.size() == 1);
  const auto& sync = report->servers[0];
  CHECK_MESSAGE(!sync.error, (sync.error ? sync.error->message : ""));
  CHECK(sync.pushed == 5);
  CHECK(sync.refused == 1);
  CHECK(sync.pending == 0);
  CHECK(count(admin, "SELECT COUNT(*) FROM class_events WHERE user_name = '" + eve + "'") == 5);
  CHECK(count(admin, "SELECT COUNT(*) FROM class_events WHERE user_name = '" + sam + "'") == 0);

  // Through the pooler eve reads only her own rows and writes none.
  Database eveServer = openAt(eveUrl);
  CHECK(count(eveServer, "SELECT COUNT(*) FROM class_events") == 5);
  CHECK(count(eveServer, "SELECT COUNT(*) FROM class_members WHERE user_name <> '" + eve + "'") == 0);
  CHECK_FALSE(eveServer.exec("DELETE FROM class_events"));
  CHECK(count(admin, "SELECT COUNT(*) FROM class_events") == 5);
}
