// Who reads a study on a class server: its owner while she coordinates a class. Demoted in every
// class (an audited role change), her login reads none of it — the study, its participants, their
// A/B keys, their ratings, its withdrawals — through the program or psql; made coordinator again,
// she reads it again. Another coordinator never reads a study she does not own.
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/study_store.h"
#include "db/study_withdrawal.h"
#include "secure_class.h"
#include "study_server_snapshot.h"
#include "test_support.h"

using namespace at;
using namespace at::db;

namespace {

const std::vector<std::string> kStudyTables = {
    "studies", "study_participants", "study_trials", "study_ratings",
    "class_audit WHERE action LIKE 'study\\_%'"};

// The rows of each study table `login` reads, through its own connection.
std::vector<std::int64_t> rowsRead(Database& login) {
  std::vector<std::int64_t> out;
  for (const std::string& t : kStudyTables) out.push_back(test::scalarCount(login, "SELECT COUNT(*) FROM " + t));
  return out;
}

// The same through psql as the login of `url`; empty when psql is not installed.
std::vector<std::int64_t> rowsReadWithPsql(const std::string& url) {
  int status = 0;
  test::runCommand("psql --version > /dev/null 2>&1", status);
  if (status != 0) return {};
  std::vector<std::int64_t> out;
  for (const std::string& t : kStudyTables) {
    const std::string out1 =
        test::runCommand("psql '" + url + "' -X -q -At -v ON_ERROR_STOP=1 -c \"SELECT COUNT(*) FROM " + t + "\" 2>&1", status);
    REQUIRE_MESSAGE(status == 0, out1);
    out.push_back(std::stoll(out1));
  }
  return out;
}

}  // namespace

TEST_CASE("StudyReaders_ADemotedCoordinatorReadsNoneOfHerStudies_PromotedAgainSheDoes") {
  auto url = test::freshPostgresDatabase("the study readers test");
  if (!url) return;
  test::SecureClass c(*url);
  Database ada = test::openAt(c.coordinatorUrl);
  const quiz::StudyProtocol p = test::paperSurvey();
  REQUIRE(saveStudy(ada, p));
  auto first = enrolOrResume(ada, p, "P0", p.groups[0]);
  REQUIRE(first);
  RatingRecord r;
  r.position = 0;
  r.item = p.items[0].id;
  r.ratingAsShown = 3;
  REQUIRE(recordRating(ada, *first, r));
  REQUIRE(enrolOrResume(ada, p, "P1", p.groups[0]));
  REQUIRE(withdrawStudyParticipant(ada, p.id, "P1", StudyWithdrawalKind::Withdrawn, "asked to stop", std::nullopt));

  // As the owner and a coordinator: every table has her rows.
  const std::vector<std::int64_t> owned = rowsRead(ada);
  for (std::int64_t n : owned) CHECK(n > 0);
  const std::vector<std::int64_t> ownedPsql = rowsReadWithPsql(c.coordinatorUrl);
  if (!ownedPsql.empty()) CHECK(ownedPsql == owned);

  // Another coordinator reads none of a study she does not own.
  const std::string ben = test::uniqueLogin("ben");
  const std::string benUrl = c.account(ada, ben, ClassRole::Coordinator);
  Database benDb = test::openAt(benUrl);
  for (std::int64_t n : rowsRead(benDb)) CHECK(n == 0);

  // ben demotes ada (audited); she reads nothing of her studies any more, program or psql.
  REQUIRE(setMemberRole(benDb, c.code, "", c.coordinator, ClassRole::Instructor));
  const std::string before = test::studySnapshot(c.admin);
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_audit WHERE action = 'role' AND actor = '" + ben +
                                       "' AND target = '" + c.coordinator + "' AND new_value = 'instructor'") == 1);
  for (std::int64_t n : rowsRead(ada)) CHECK(n == 0);
  const std::vector<std::int64_t> demotedPsql = rowsReadWithPsql(c.coordinatorUrl);
  for (std::int64_t n : demotedPsql) CHECK(n == 0);
  auto found = findStudy(ada, p.id);
  CHECK((!found || !*found));  // the program finds no such study for her
  CHECK(test::studySnapshot(c.admin) == before);  // her reads changed nothing; the administrator reads it all

  // Made coordinator again, she reads what she read before.
  REQUIRE(setMemberRole(benDb, c.code, "", c.coordinator, ClassRole::Coordinator));
  CHECK(rowsRead(ada) == owned);
}
