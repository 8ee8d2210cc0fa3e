// The desktop sends a class member's records to the class server by itself (class_sync.h): a
// lesson started in the desktop reaches a real PostgreSQL server without `anatomy-tutor sync`.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include "db/class_server.h"
#include "db/course_store.h"
#include "headless_desktop.h"
#include "test_databases.h"
#include "test_support.h"

using json = nlohmann::json;
using namespace at;

TEST_CASE("A lesson started in the desktop by a class member reaches the class server on its own") {
  auto url = test::freshPostgresDatabase("the desktop class test");
  if (!url) return;
  test::TempDir dir("desktop-class");
  const auto local = dir / "laptop.db";
  std::string code;
  {
    auto server = db::openDatabase(*url);
    REQUIRE(server);
    REQUIRE(db::seedCourses(*server, test::sourceDir() / "data" / "courses"));  // the server judges events by it
    auto made = db::createClass(*server, "Ear anatomy", "dr_ada");
    REQUIRE(made);
    code = made->code;
    REQUIRE(db::joinClass(*server, code, "tester"));
    auto laptop = db::openDatabase(local.string());
    REQUIRE(laptop);
    REQUIRE(db::rememberMembership(*laptop, {"tester", code, *url, db::ClassRole::Student}));
  }
  test::HeadlessOptions options;
  options.db = local;
  options.user = "tester";
  const json actions = {{{"do", "lessons"}, {"course", "temporal_bone"}},
                        {{"do", "lesson"}, {"course", "temporal_bone"}, {"lesson", "inner_ear"}},
                        {{"do", "lesson_next"}}};
  const auto run = test::runHeadless({{"actions", actions}}, options);
  INFO(run.messages);
  REQUIRE(run.exitCode == 0);
  REQUIRE(test::eventsOf(run, "lesson_started").size() == 1);
  CHECK(test::postgresValue(*url, "SELECT COUNT(*) FROM class_events WHERE class_code = '" + code +
                                      "' AND user_name = 'tester' AND kind = 'lesson_started' AND lesson_id = 'inner_ear'") ==
        "1");
  auto laptop = db::openDatabase(local.string());
  REQUIRE(laptop);
  auto counts = db::outboxCounts(*laptop);
  REQUIRE(counts);
  CHECK(counts->pending == 0);
  CHECK(counts->sent == 1);
}
