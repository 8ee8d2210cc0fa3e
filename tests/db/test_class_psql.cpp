// The attacks a student makes with psql itself (not the program's connection): logged in as
// herself, she can promote no one, act as no one, forge no event under another name, read no one
// else's answers, no A/B key, no exam key, and update, delete, truncate or drop nothing — every
// table of the server stays byte-identical — while her own event, sent through the server's
// function, still lands.
#include <doctest/doctest.h>

#include <ctime>
#include <string>
#include <vector>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/study_store.h"
#include "db/study_withdrawal.h"
#include "quiz/study_protocol.h"
#include "secure_class.h"
#include "test_support.h"
#include "uuid.h"  // db/src

using namespace at;
using namespace at::db;

namespace {

struct Psql {
  int status = -1;
  std::string output;  // stdout and stderr together
};

// psql as the login of `url`, one statement, stopping at the first error.
Psql psql(const std::string& url, const std::string& sql) {
  std::string quotedSql;
  for (char c : sql) quotedSql += c == '\'' ? std::string("'\\''") : std::string(1, c);
  Psql r;
  r.output = test::runCommand("psql '" + url + "' -X -q -At -v ON_ERROR_STOP=1 -c '" + quotedSql + "' 2>&1", r.status);
  return r;
}

using test::everyServerRow;

}  // namespace

TEST_CASE("ClassPsql_AStudentWithPsqlItselfChangesNothingAndReadsOnlyHerOwnRows") {
  int status = 0;
  test::runCommand("psql --version > /dev/null 2>&1", status);
  if (status != 0) {
    test::skipf("the psql attack test needs psql (Debian package postgresql-client)");
    return;
  }
  auto url = test::freshPostgresDatabase("the psql attack test");
  if (!url) return;
  test::SecureClass c(*url);
  {  // A study with a participant (their A/B keys), owned by the coordinator, run by her login.
    Database coordinator = test::openAt(c.coordinatorUrl);
    auto survey = quiz::loadStudyProtocol((test::sourceDir() / "data/studies/paper_survey.json").string());
    REQUIRE(survey);
    REQUIRE(saveStudy(coordinator, *survey));
    REQUIRE(enrolOrResume(coordinator, *survey, "P0", survey->groups[0]));
  }
  // eve's answer on the server, through the administrator (who may name her).
  const std::int64_t now = std::int64_t(std::time(nullptr));
  const std::string started = "SELECT at_record_event('" + newUuid() + "', '" + c.code + "', '%s', 'lesson_started', " +
                              std::to_string(now) + ", 'toy.ossicles', '', '', NULL, NULL, '{}')";
  auto eveStarted = started;
  eveStarted.replace(eveStarted.find("%s"), 2, c.eve);
  REQUIRE(c.admin.exec(eveStarted));
  REQUIRE(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE user_name = '" + c.eve + "'") == 1);

  const std::string before = everyServerRow(c.admin);
  const std::string q = "'" + c.code + "'";
  const std::vector<std::string> attacks = {
      // promote and impersonate
      "SELECT at_set_role(" + q + ", '" + c.sam + "', 'coordinator', '')",
      "SELECT at_set_role(" + q + ", '" + c.sam + "', 'coordinator', '" + c.coordinator + "')",
      "SELECT at_create_account(" + q + ", 'mallory_x', 'coordinator', 'aaaaaaaaaaaaaaaaaaaa', '')",
      "UPDATE class_members SET role = 'coordinator' WHERE user_name = '" + c.sam + "'",
      "SET ROLE at_class_owner", "SET SESSION AUTHORIZATION " + c.coordinator, "GRANT at_class_owner TO " + c.sam,
      "ALTER ROLE " + c.coordinator + " PASSWORD 'taken_over_taken_over'", "ALTER ROLE " + c.sam + " SUPERUSER",
      // forge an outbox event as a raw row
      "INSERT INTO class_events (uuid, class_code, user_name, kind, occurred_at, received_at) VALUES ('" + newUuid() + "', " + q +
          ", '" + c.eve + "', 'answer', 0, 0)",
      // read what is not hers: the exam keys, the locate keys
      "SELECT * FROM class_exam_keys", "SELECT * FROM class_exam_locate_keys",
      // update, delete, truncate, drop, and change the rules
      "UPDATE class_events SET correct = 0", "DELETE FROM class_events", "TRUNCATE class_events", "TRUNCATE class_audit",
      "DROP TABLE class_events", "DROP TABLE study_trials CASCADE", "UPDATE study_ratings SET rating_ab = 6 - rating_ab",
      "UPDATE study_trials SET a_condition = b_condition", "DELETE FROM class_audit",
      "ALTER TABLE class_events DISABLE ROW LEVEL SECURITY", "DROP POLICY own_or_taught ON class_events",
      "CREATE OR REPLACE FUNCTION at_is_account() RETURNS boolean LANGUAGE sql AS 'SELECT false'",
      "CREATE TABLE class_events_copy AS SELECT * FROM class_events",
      // the study, as if she ran it
      "SELECT at_register_study('mine', '', 'phantom', 1, '{}', '')", "SELECT at_draw_study_row('wdt_vs_bare_phantom')",
      "SELECT at_record_rating('wdt_vs_bare_phantom', 'P0', 1, 0, 'shape', 5, 0, 0, 0, 0, '', NULL, NULL, NULL, NULL)"};
  for (const std::string& sql : attacks) {
    CAPTURE(sql);
    const Psql r = psql(c.samUrl, sql);
    CAPTURE(r.output);
    CHECK(r.status != 0);
    CHECK(r.output.find("ERROR:") != std::string::npos);
  }
  // An answer under eve's name, sent through the server's function, is refused with its reason.
  const Psql asEve = psql(c.samUrl, "SELECT at_record_event('" + newUuid() + "', " + q + ", '" + c.eve + "', 'answer', " +
                                        std::to_string(now) + ", 'toy.ossicles', 'toy.ossicles.name_stapes', 'stapes', 0, 0.0, '{}')");
  CHECK(asEve.status == 0);
  CHECK(asEve.output.rfind("refused: ", 0) == 0);
  CHECK(asEve.output.find("but was sent by the login " + c.sam) != std::string::npos);
  CHECK(everyServerRow(c.admin) == before);

  // What she reads with psql: nothing of eve's, no study row (A/B keys), no audit.
  for (const std::string& sql :
       {std::string("SELECT count(*) FROM class_events WHERE user_name <> current_user"), std::string("SELECT count(*) FROM class_members WHERE user_name <> current_user"),
        std::string("SELECT count(*) FROM study_trials"), std::string("SELECT count(*) FROM study_ratings"),
        std::string("SELECT count(*) FROM studies"), std::string("SELECT count(*) FROM class_audit"),
        std::string("SELECT count(*) FROM class_exam_answers")}) {
    CAPTURE(sql);
    const Psql r = psql(c.samUrl, sql);
    CAPTURE(r.output);
    CHECK(r.status == 0);
    CHECK(r.output == "0\n");
  }
  // Her own event still lands, sent as herself through the server's function.
  auto samStarted = started;
  samStarted.replace(samStarted.find("%s"), 2, c.sam);
  samStarted.replace(samStarted.find("SELECT at_record_event('") + 24, 36, newUuid());
  const Psql own = psql(c.samUrl, samStarted);
  CAPTURE(own.output);
  CHECK(own.status == 0);
  CHECK(own.output == "stored\n");
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE user_name = '" + c.sam + "'") == 1);
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE user_name = '" + c.eve + "'") == 1);
}
