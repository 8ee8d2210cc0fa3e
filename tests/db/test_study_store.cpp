#include <doctest/doctest.h>

#include <set>

#include "db/database.h"
#include "db/study_store.h"
#include "quiz/study_protocol.h"
#include "test_databases.h"
#include "test_support.h"

using namespace at;

namespace {
quiz::StudyProtocol protocol(std::uint64_t seed = 5) {
  auto p = quiz::loadStudyProtocol((test::sourceDir() / "data/studies/paper_survey.json").string());
  REQUIRE(p.has_value());
  p->seed = seed;
  return *p;
}
}  // namespace

TEST_CASE("StudyStore_EnrolParticipants_StoresBlindedCounterbalancedTrials") {
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  const auto p = protocol();
  REQUIRE(db::saveStudy(*db, p).has_value());
  std::set<std::string> firstStructures;
  for (int i = 0; i < 4; ++i) {
    auto part = db::enrolOrResume(*db, p, "P" + std::to_string(i), i % 2 ? "medical" : "non-medical");
    REQUIRE_MESSAGE(part.has_value(), part.error().message);
    CHECK(part->enrolmentIndex == i);
    REQUIRE(part->trials.size() == p.structures.size());
    firstStructures.insert(part->trials[0].structure);
    for (const auto& t : part->trials) {
      CHECK(t.aCondition != t.bCondition);
      CHECK(t.presetA == t.structure + (t.aCondition == "wdt" ? "_wdt" : "_bare"));
    }
  }
  CHECK(firstStructures.size() == 4);  // the Latin square rotates the first structure
  // Resume keeps the plan and counts the session.
  auto again = db::enrolOrResume(*db, p, "P1", "medical");
  REQUIRE(again.has_value());
  CHECK(again->session == 2);
  CHECK(again->enrolmentIndex == 1);
  // Wrong group and unknown group are refused.
  CHECK_FALSE(db::enrolOrResume(*db, p, "P1", "non-medical").has_value());
  auto unknown = db::enrolOrResume(*db, p, "P9", "surgeons");
  REQUIRE_FALSE(unknown.has_value());
  CHECK(unknown.error().message.find("surgeons") != std::string::npos);
}

TEST_CASE("StudyStore_DesignChangeAfterParticipants_IsRefusedAndNothingChanges") {
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  auto p = protocol();
  REQUIRE(db::saveStudy(*db, p).has_value());
  REQUIRE(db::enrolOrResume(*db, p, "P0", "medical").has_value());
  auto changed = p;
  changed.items.pop_back();
  auto s = db::saveStudy(*db, changed);
  REQUIRE_FALSE(s.has_value());
  CHECK(s.error().message.find("already has 1 participant") != std::string::npos);
  auto stored = db::findStudy(*db, p.id);
  REQUIRE(stored.has_value());
  REQUIRE(stored->has_value());
  CHECK((*stored)->items.size() == p.items.size());
  // A title change is allowed.
  auto retitled = p;
  retitled.title = "Renamed";
  CHECK(db::saveStudy(*db, retitled).has_value());
}

TEST_CASE("StudyStore_RatingsAreUnblindedOnExport") {
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  const auto p = protocol();
  REQUIRE(db::saveStudy(*db, p).has_value());
  auto part = db::enrolOrResume(*db, p, "always-wdt", "medical");
  REQUIRE(part.has_value());
  for (const auto& t : part->trials) {
    for (const auto& item : p.items) {
      db::RatingRecord r;
      r.position = t.position;
      r.item = item.id;
      r.ratingAsShown = t.aCondition == "wdt" ? 1 : 5;  // always prefers the WDT view
      REQUIRE(db::recordRating(*db, p.id, "always-wdt", r).has_value());
    }
  }
  REQUIRE(db::markParticipantComplete(*db, p.id, "always-wdt").has_value());
  auto rows = db::studyResponseRows(*db, p);
  REQUIRE(rows.has_value());
  CHECK(rows->size() == p.structures.size() * p.items.size());
  std::set<int> shown;
  for (const auto& r : *rows) {
    CHECK(r.rating == 1);
    shown.insert(r.ratingAb);
    CHECK(r.participantComplete);
  }
  CHECK(shown == std::set<int>{1, 5});  // A was WDT for some structures and bare for others
  auto completion = db::studyCompletion(*db, p.id);
  REQUIRE(completion.has_value());
  REQUIRE(completion->size() == 1);
  CHECK((*completion)[0].complete);
  CHECK((*completion)[0].ratingsGiven == (*completion)[0].ratingsExpected);
}

TEST_CASE("StudyStore_ResumedParticipant_EachRatingKeepsTheSessionItWasGivenIn") {
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  const auto p = protocol();
  REQUIRE(db::saveStudy(*db, p).has_value());
  REQUIRE(db::enrolOrResume(*db, p, "P0", "medical").has_value());
  db::RatingRecord r;
  r.item = p.items[0].id;
  r.ratingAsShown = 2;
  REQUIRE(db::recordRating(*db, p.id, "P0", r).has_value());
  REQUIRE(db::recordTrialViewing(*db, p.id, "P0", 0, 100, 200, 1, "", false).has_value());
  REQUIRE(db::enrolOrResume(*db, p, "P0", "medical").has_value());  // session 2
  r.item = p.items[1].id;
  REQUIRE(db::recordRating(*db, p.id, "P0", r).has_value());
  auto rows = db::studyResponseRows(*db, p);
  REQUIRE(rows.has_value());
  REQUIRE(rows->size() == 2);
  CHECK((*rows)[0].session == 1);
  CHECK((*rows)[1].session == 2);
  CHECK_FALSE((*rows)[0].viewingMeasured);  // shown as files: the times are not known
  auto participants = db::studyParticipantRows(*db, p.id);
  REQUIRE(participants.has_value());
  REQUIRE(participants->size() == 1);
  CHECK((*participants)[0].sessions == 2);
}

TEST_CASE("StudyStore_RatingsFromBeforeSessionsWereKept_MigrateToSessionOneOrUnknown") {
  test::TempDir dir;
  const std::string path = test::freshDatabase(dir, "old.db");
  const auto p = protocol();
  {
    db::OpenOptions options;
    options.targetVersion = 6;
    auto old = db::Database::open(path, options);
    REQUIRE(old.has_value());
    REQUIRE(db::saveStudy(*old, p).has_value());
    for (const char* who : {"once", "twice"}) {
      REQUIRE(old->exec(std::string("INSERT INTO study_participants (study_id, participant_id, group_name, enrolment_index,"
                                    " session) VALUES ('") + p.id + "', '" + who + "', 'medical', " +
                        (who[0] == 'o' ? "0, 1" : "1, 2") + ");"));
      REQUIRE(old->exec(std::string("INSERT INTO study_trials (study_id, participant_id, position, structure, a_condition,"
                                    " b_condition, preset_a, preset_b) VALUES ('") + p.id + "', '" + who +
                        "', 0, 'cochlea', 'wdt', 'bare', 'cochlea_wdt', 'cochlea_bare');"));
      REQUIRE(old->exec(std::string("INSERT INTO study_ratings (study_id, participant_id, position, item, rating_ab)"
                                    " VALUES ('") + p.id + "', '" + who + "', 0, 'shape', 2);"));
    }
  }
  auto db = db::Database::open(path);
  REQUIRE(db.has_value());
  auto rows = db::studyResponseRows(*db, p);
  REQUIRE(rows.has_value());
  REQUIRE(rows->size() == 2);
  CHECK((*rows)[0].participantId == "once");
  CHECK((*rows)[0].session == 1);
  CHECK((*rows)[1].session == 0);  // resumed before the upgrade: which session is not known
  CHECK((*rows)[1].viewingMeasured);
}

TEST_CASE("StudyStore_ParticipantIdsThatAreNoValidRecordNames_AreRefused") {
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  const auto p = protocol();
  REQUIRE(db::saveStudy(*db, p).has_value());
  for (const char* bad : {"", "=cmd|'calc'", "a b", "-P1", "P1,2"}) {
    CAPTURE(bad);
    auto e = db::enrolOrResume(*db, p, bad, "medical");
    REQUIRE_FALSE(e.has_value());
    CHECK(e.error().message.find("letters, digits") != std::string::npos);
  }
  CHECK(db::enrolOrResume(*db, p, "site-2_P07", "medical").has_value());
}
