#include <doctest/doctest.h>

#include <set>

#include "db/database.h"
#include "db/study_store.h"
#include "quiz/study_protocol.h"
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
  auto db = db::Database::open((dir / "t.db").string());
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
  auto db = db::Database::open((dir / "t.db").string());
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
  auto db = db::Database::open((dir / "t.db").string());
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
      REQUIRE(db::recordRating(*db, *part, r).has_value());
    }
  }
  REQUIRE(db::markParticipantComplete(*db, *part).has_value());
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
