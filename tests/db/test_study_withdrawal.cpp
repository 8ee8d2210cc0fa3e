// A study's owner reads it and withdraws or excludes its participants: on a class server only the
// coordinator whose login owns it, audited; everywhere the participant leaves every export and
// Table 2 with the reason kept, and nothing more is recorded for them.
#include <doctest/doctest.h>

#include <random>
#include <string>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/study_store.h"
#include "db/study_withdrawal.h"
#include "quiz/study_protocol.h"
#include "quiz/study_report.h"
#include "secure_class.h"
#include "test_support.h"

using namespace at;
using namespace at::db;

namespace {

quiz::StudyProtocol paperSurvey() {
  auto p = quiz::loadStudyProtocol((test::sourceDir() / "data/studies/paper_survey.json").string());
  REQUIRE(p.has_value());
  return *p;
}

// Enrols `count` participants (alternating groups) and rates every item of every trial with
// ratings drawn from `random`.
void enrolAndRate(Database& db, const quiz::StudyProtocol& p, int count, std::mt19937& random) {
  for (int i = 0; i < count; ++i) {
    auto part = enrolOrResume(db, p, "P" + std::to_string(i), p.groups[std::size_t(i) % p.groups.size()]);
    REQUIRE_MESSAGE(part, (part ? "" : part.error().message));
    for (const auto& t : part->trials)
      for (const auto& item : p.items) {
        RatingRecord r;
        r.position = t.position;
        r.item = item.id;
        r.ratingAsShown = 1 + int(random() % 5);
        REQUIRE(recordRating(db, *part, r));
      }
  }
}

// The export's rows (what Table 2 is computed from) of participants other than `left`.
std::vector<quiz::StudyResponseRow> rowsWithout(std::vector<quiz::StudyResponseRow> rows, const std::string& left) {
  std::erase_if(rows, [&](const quiz::StudyResponseRow& r) { return r.participantId == left; });
  return rows;
}

}  // namespace

TEST_CASE("StudyWithdrawal_OnAFile_TheParticipantLeavesExportsAndTable2_ReasonKept_Audited_NothingMoreRecorded") {
  test::TempDir dir;
  Database db = test::openAt(test::freshDatabase(dir));
  const std::uint64_t seed = test::freshSeed("StudyWithdrawal_OnAFile");
  std::mt19937 random{unsigned(seed)};
  const quiz::StudyProtocol p = paperSurvey();
  REQUIRE(saveStudy(db, p));
  enrolAndRate(db, p, 4, random);
  auto before = studyResponseRows(db, p);
  REQUIRE(before);
  const std::string left = "P" + std::to_string(random() % 4);
  CAPTURE(left);

  CHECK_FALSE(withdrawStudyParticipant(db, p.id, left, StudyWithdrawalKind::Withdrawn, "  ", "dr_ada"));
  CHECK_FALSE(withdrawStudyParticipant(db, p.id, "P9", StudyWithdrawalKind::Withdrawn, "consent", "dr_ada"));
  REQUIRE(withdrawStudyParticipant(db, p.id, left, StudyWithdrawalKind::Withdrawn, "consent withdrawn by e-mail", "dr_ada"));
  CHECK_FALSE(withdrawStudyParticipant(db, p.id, left, StudyWithdrawalKind::Excluded, "again", "dr_ada"));

  auto after = studyResponseRows(db, p);
  REQUIRE(after);
  const auto expected = rowsWithout(*before, left);
  CHECK(after->size() == expected.size());
  CHECK(quiz::summaryCsv(quiz::summariseStudy(p, *after)) == quiz::summaryCsv(quiz::summariseStudy(p, expected)));
  auto participants = studyParticipantRows(db, p.id);
  REQUIRE(participants);
  CHECK(participants->size() == 3);
  // The rows stay (the participant's data is not silently lost), the reason is listed, audited.
  CHECK(test::scalarCount(db, "SELECT COUNT(*) FROM study_ratings WHERE participant_id = '" + left + "'") ==
        std::int64_t(p.structures.size() * p.items.size()));
  auto withdrawals = studyWithdrawals(db, p.id);
  REQUIRE(withdrawals);
  REQUIRE(withdrawals->size() == 1);
  CHECK(withdrawals->front().participantId == left);
  CHECK(withdrawals->front().reason == "consent withdrawn by e-mail");
  auto completion = studyCompletion(db, p.id);
  REQUIRE(completion);
  for (const auto& c : *completion) CHECK(c.withdrawal.has_value() == (c.participantId == left));
  CHECK(test::scalarCount(db, "SELECT COUNT(*) FROM class_audit WHERE action = 'study_withdrawn' AND actor = 'dr_ada'"
                              " AND target = '" + p.id + " " + left + "'") == 1);
  // Nothing more is recorded for them; the others' counterbalancing rows stay where they were.
  auto resumed = enrolOrResume(db, p, left, "medical");
  REQUIRE_FALSE(resumed);
  CHECK(resumed.error().message.find("withdrawn") != std::string::npos);
  auto next = enrolOrResume(db, p, "P4", p.groups[0]);
  REQUIRE(next);
  CHECK(next->enrolmentIndex == 4);
}

TEST_CASE("StudyWithdrawal_OnTheServer_OnlyTheOwningCoordinatorReadsAndWithdraws_StudentsReadNothing") {
  auto url = test::freshPostgresDatabase("the study withdrawal test");
  if (!url) return;
  test::SecureClass c(*url);
  const quiz::StudyProtocol p = paperSurvey();
  REQUIRE(saveStudy(c.admin, p));
  REQUIRE(setStudyOwner(c.admin, p.id, c.coordinator));
  std::mt19937 random(7);
  enrolAndRate(c.admin, p, 3, random);
  Database coordinator = test::openAt(c.coordinatorUrl);
  Database instructor = test::openAt(c.instructorUrl);
  Database sam = test::openAt(c.samUrl);

  // The owner reads the study and its blinded ratings; no one else reads a row of it.
  auto rows = studyResponseRows(coordinator, p);
  REQUIRE_MESSAGE(rows, (rows ? "" : rows.error().message));
  CHECK(rows->size() == 3 * p.structures.size() * p.items.size());
  for (Database* other : {&instructor, &sam})
    for (const char* table : {"studies", "study_participants", "study_trials", "study_ratings"})
      CHECK(test::scalarCount(*other, std::string("SELECT COUNT(*) FROM ") + table) == 0);

  // Only the owner withdraws; a student or the instructor is refused and nothing changes.
  CHECK_FALSE(withdrawStudyParticipant(sam, p.id, "P1", StudyWithdrawalKind::Withdrawn, "I say so", std::nullopt));
  CHECK_FALSE(withdrawStudyParticipant(instructor, p.id, "P1", StudyWithdrawalKind::Excluded, "protocol", std::nullopt));
  CHECK_FALSE(withdrawStudyParticipant(sam, p.id, "P1", StudyWithdrawalKind::Withdrawn, "as her", c.coordinator));
  CHECK_FALSE(sam.exec("UPDATE study_participants SET withdrawn_at = 'x'"));
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM study_participants WHERE withdrawn_at IS NOT NULL") == 0);
  auto excluded = withdrawStudyParticipant(coordinator, p.id, "P1", StudyWithdrawalKind::Excluded,
                                           "did not meet the inclusion criteria", std::nullopt);
  REQUIRE_MESSAGE(excluded, (excluded ? "" : excluded.error().message));
  auto after = studyResponseRows(coordinator, p);
  REQUIRE(after);
  CHECK(after->size() == 2 * p.structures.size() * p.items.size());
  CHECK(quiz::summaryCsv(quiz::summariseStudy(p, *after)) ==
        quiz::summaryCsv(quiz::summariseStudy(p, rowsWithout(*rows, "P1"))));
  CHECK(test::scalarCount(coordinator, "SELECT COUNT(*) FROM class_audit WHERE action = 'study_excluded' AND actor = '" +
                                           c.coordinator + "'") == 1);
  CHECK(test::scalarCount(sam, "SELECT COUNT(*) FROM class_audit") == 0);
}

TEST_CASE("StudyWithdrawal_MergeCarriesWithdrawals_AParticipantWithdrawnOnAnyMachineStaysWithdrawn") {
  test::TempDir dir;
  const std::uint64_t seed = test::freshSeed("StudyWithdrawal_MergeCarriesWithdrawals");
  std::mt19937 random{unsigned(seed)};
  const quiz::StudyProtocol p = paperSurvey();
  Database lab = test::openAt((dir / "lab.db").string());
  REQUIRE(saveStudy(lab, p));
  enrolAndRate(lab, p, 4, random);
  const std::string left = "P" + std::to_string(random() % 4);
  CAPTURE(left);
  Database merged = test::openAt((dir / "merged.db").string());
  // Merged once before the withdrawal, then again after it: the second merge carries it.
  auto first = mergeStudy(merged, {StudyMergeSource{"lab.db", &lab, nullptr}}, p.id);
  REQUIRE_MESSAGE(first, (first ? "" : first.error().message));
  CHECK(first->sources.at(0).withdrawals == 0);
  REQUIRE(withdrawStudyParticipant(lab, p.id, left, StudyWithdrawalKind::Excluded, "colour blind", "dr_ada"));
  auto second = mergeStudy(merged, {StudyMergeSource{"lab.db", &lab, nullptr}}, p.id);
  REQUIRE_MESSAGE(second, (second ? "" : second.error().message));
  CHECK(second->sources.at(0).alreadyThere == 4);
  CHECK(second->sources.at(0).withdrawals == 1);
  // Into a fresh file in one go: the same.
  Database fresh = test::openAt((dir / "fresh.db").string());
  auto once = mergeStudy(fresh, {StudyMergeSource{"lab.db", &lab, nullptr}}, p.id);
  REQUIRE(once);
  CHECK(once->sources.at(0).withdrawals == 1);
  for (Database* db : {&merged, &fresh}) {
    auto withdrawals = studyWithdrawals(*db, p.id);
    REQUIRE(withdrawals);
    REQUIRE(withdrawals->size() == 1);
    CHECK(withdrawals->front().participantId == left);
    CHECK(withdrawals->front().reason == "colour blind");
    auto rows = studyResponseRows(*db, p);
    REQUIRE(rows);
    auto labRows = studyResponseRows(lab, p);
    REQUIRE(labRows);
    CHECK(rows->size() == labRows->size());  // the export leaves them out, as on the lab machine
    for (const auto& r : *rows) CHECK(r.participantId != left);
  }
  // Merging again changes nothing more.
  auto third = mergeStudy(merged, {StudyMergeSource{"lab.db", &lab, nullptr}}, p.id);
  REQUIRE(third);
  CHECK(third->sources.at(0).withdrawals == 0);
}
