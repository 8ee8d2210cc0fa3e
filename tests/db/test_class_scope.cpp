// Row-level security keeps a class to itself: an instructor or coordinator of one class reads that
// class's members, events and audit, and nothing of another class on the same server — through the
// program and with psql as their own login.
#include <doctest/doctest.h>

#include <ctime>
#include <string>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/class_accounts.h"
#include "db/class_server.h"
#include "secure_class.h"
#include "test_databases.h"
#include "test_support.h"
#include "uuid.h"  // db/src

using namespace at;
using namespace at::db;

TEST_CASE("ClassScope_AnInstructorOrCoordinatorOfOneClassReadsNothingOfAnother") {
  auto url = test::freshPostgresDatabase("the class scope test");
  if (!url) return;
  test::SecureClass mine(*url);  // lee teaches it, ada coordinates it, sam and eve learn in it
  // Another class on the same server, its own coordinator and student, with work of its own.
  const std::string otherCoordinator = test::uniqueLogin("kay"), otherStudent = test::uniqueLogin("tom");
  auto other = createClass(mine.admin, "Another class", otherCoordinator);
  REQUIRE(other);
  auto tom = createClassAccount(mine.admin, other->code, otherStudent, ClassRole::Student, std::nullopt);
  REQUIRE(tom);
  REQUIRE(tom->password);
  const std::string tomUrl = test::loginUrl(*url, otherStudent, *tom->password);
  Database tomDb = test::openAt(tomUrl);
  const std::int64_t now = std::int64_t(std::time(nullptr));
  for (const std::string& sql :
       {"SELECT at_record_event('" + newUuid() + "', '" + other->code + "', '" + otherStudent +
            "', 'lesson_started', " + std::to_string(now) + ", 'toy.ossicles', '', '', NULL, NULL, '{}')",
        "SELECT at_record_event('" + newUuid() + "', '" + other->code + "', '" + otherStudent + "', 'answer', " +
            std::to_string(now) + ", 'toy.ossicles', 'toy.ossicles.name_stapes', '', 1, 1.0, '{\"answer\": {\"text\": \"stapes\"}}')"}) {
    auto s = tomDb.prepare(sql);
    REQUIRE(s);
    REQUIRE(*s->step());
    CHECK(s->text(0) == "stored");
  }
  // And work in her own class, so that reading it is shown to work.
  Database samDb = test::openAt(mine.samUrl);
  {
    auto s = samDb.prepare("SELECT at_record_event('" + newUuid() + "', '" + mine.code + "', '" + mine.sam +
                           "', 'lesson_started', " + std::to_string(now) + ", 'toy.ossicles', '', '', NULL, NULL, '{}')");
    REQUIRE(s);
    REQUIRE(*s->step());
    CHECK(s->text(0) == "stored");
  }
  const std::string otherCode = "'" + other->code + "'", myCode = "'" + mine.code + "'";
  for (const auto& [who, login] : {std::pair{mine.instructorUrl, mine.instructor}, std::pair{mine.coordinatorUrl, mine.coordinator}}) {
    CAPTURE(login);
    Database db = test::openAt(who);
    CHECK(test::scalarCount(db, "SELECT COUNT(*) FROM class_events WHERE class_code = " + myCode) >= 1);
    CHECK(test::scalarCount(db, "SELECT COUNT(*) FROM class_members WHERE class_code = " + myCode) >= 4);
    for (const char* table : {"class_events", "class_members", "class_audit", "classes"}) {
      CAPTURE(table);
      const std::string column = std::string(table) == "classes" ? "code" : "class_code";
      CHECK(test::scalarCount(db, "SELECT COUNT(*) FROM " + std::string(table) + " WHERE " + column + " = " + otherCode) == 0);
    }
    auto progress = classProgress(db, other->code, "");
    REQUIRE_FALSE(progress);
    CAPTURE(progress.error().message);
    CHECK(progress.error().message.find(other->code) != std::string::npos);
  }
  // The rows are there: the administrator reads them.
  CHECK(test::scalarCount(mine.admin, "SELECT COUNT(*) FROM class_events WHERE class_code = " + otherCode) == 2);
}
