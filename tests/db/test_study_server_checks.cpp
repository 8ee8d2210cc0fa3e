// What a study's writes are checked against on a class server: the counterbalancing row computed
// there equals quiz::planParticipant for any design size, participant and seed; a participant's
// trials that are not the row the server drew (or a row already given) are refused and change
// nothing; a coordinator demoted in every class writes nothing more to the studies she owns.
#include <doctest/doctest.h>

#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/study_store.h"
#include "db/study_withdrawal.h"
#include "quiz/study_design.h"
#include "quiz/study_protocol.h"
#include "secure_class.h"
#include "study_server_snapshot.h"
#include "test_support.h"

using namespace at;
using namespace at::db;
using nlohmann::json;

namespace {

using test::paperSurvey;
using test::studySnapshot;

// The trials of row `row` of `p`'s design, as the laptop sends them (study_server_writes.cpp).
json trialsOfRow(const quiz::StudyProtocol& p, std::size_t row) {
  json trials = json::array();
  for (const quiz::TrialPlan& plan : quiz::planParticipant(p.structures.size(), row, p.seed)) {
    const std::string& s = p.structures[plan.structureIndex];
    const int a = plan.aIsFirstCondition ? 0 : 1, b = 1 - a;
    trials.push_back({{"position", int(plan.position)}, {"structure", s}, {"a_condition", p.conditions[std::size_t(a)].id},
                      {"b_condition", p.conditions[std::size_t(b)].id}, {"preset_a", p.presetFor(s, a)},
                      {"preset_b", p.presetFor(s, b)}});
  }
  return trials;
}

// The server's answer to at_enrol_participant on `db`: its result, or the refusal's message.
std::string enrol(Database& db, const std::string& study, const std::string& participant, const std::string& group,
                  std::int64_t row, const std::string& trials) {
  auto s = db.prepare("SELECT at_enrol_participant(?1, ?2, ?3, ?4, ?5)");
  REQUIRE(s);
  s->bind(1, study).bind(2, participant).bind(3, group).bind(4, row).bind(5, trials);
  auto done = s->step();
  if (!done) return done.error().message;
  return s->text(0);
}

std::int64_t drawRow(Database& db, const std::string& study) {
  auto s = db.prepare("SELECT at_draw_study_row(?1)");
  REQUIRE(s);
  s->bind(1, study);
  auto done = s->step();
  REQUIRE_MESSAGE(done, (done ? "" : done.error().message));
  return s->int64(0);
}

}  // namespace

TEST_CASE("StudyChecks_TheServersCounterbalancingRowEqualsTheLaptopsForAnySizeParticipantAndSeed") {
  auto url = test::freshPostgresDatabase("the study checks test");
  if (!url) return;
  Database admin = test::openAt(*url);
  const std::uint64_t seed = test::freshSeed("StudyChecks_TheServersCounterbalancingRow");
  std::mt19937_64 random(seed);
  int rows = 0;
  for (int i = 0; i < 150; ++i) {
    const std::size_t n = 1 + random() % 16;
    const std::size_t participant = i % 3 == 0 ? random() % (2 * n + 3) : random() % 100000;
    // Seeds as a protocol stores them (0 … 2^63 - 1), the ends included.
    const std::uint64_t studySeed = i == 0 ? 0 : i == 1 ? 0x7fffffffffffffffull : random() >> 1;
    const auto laptop = quiz::planParticipant(n, participant, studySeed);
    auto s = admin.prepare("SELECT slot, structure_index, a_is_first FROM at_study_plan(?1::integer, ?2, ?3::numeric)"
                           " ORDER BY slot");
    REQUIRE(s);
    s->bind(1, std::int64_t(n)).bind(2, std::int64_t(participant)).bind(3, std::to_string(studySeed));
    std::vector<quiz::TrialPlan> server;
    while (true) {
      auto more = s->step();
      REQUIRE_MESSAGE(more, (more ? "" : more.error().message));
      if (!*more) break;
      const std::string a = s->text(2);
      server.push_back({std::size_t(s->int64(1)), std::size_t(s->int64(0)), a == "t" || a == "true" || a == "1"});
    }
    CAPTURE(n);
    CAPTURE(participant);
    CAPTURE(studySeed);
    REQUIRE(server.size() == laptop.size());
    for (std::size_t k = 0; k < n; ++k) {
      CHECK(server[k].position == laptop[k].position);
      CHECK(server[k].structureIndex == laptop[k].structureIndex);
      CHECK(server[k].aIsFirstCondition == laptop[k].aIsFirstCondition);
    }
    ++rows;
  }
  MESSAGE("seed " << seed << ": " << rows << " design rows compared");
}

TEST_CASE("StudyChecks_TrialsThatAreNotTheDrawnRowAreRefused_ARowGoesToOneParticipant_NothingChanges") {
  auto url = test::freshPostgresDatabase("the study checks test");
  if (!url) return;
  test::SecureClass c(*url);
  Database coordinator = test::openAt(c.coordinatorUrl);
  const quiz::StudyProtocol p = paperSurvey();
  REQUIRE(saveStudy(coordinator, p));
  const std::uint64_t seed = test::freshSeed("StudyChecks_TrialsThatAreNotTheDrawnRow");
  std::mt19937_64 random(seed);
  const std::size_t cycle = quiz::counterbalancingCycle(p.structures.size());
  REQUIRE(cycle > 2);

  const std::int64_t row = drawRow(coordinator, p.id);
  const std::string before = studySnapshot(c.admin);
  // Another row's trials (a row the design gives other trials), and the drawn row altered: a
  // trial's A and B swapped, two positions swapped.
  std::size_t other = std::size_t(row);
  while (trialsOfRow(p, other) == trialsOfRow(p, std::size_t(row))) other = random() % cycle;
  json swappedAB = trialsOfRow(p, std::size_t(row));
  json& t = swappedAB[random() % swappedAB.size()];
  std::swap(t["a_condition"], t["b_condition"]);
  std::swap(t["preset_a"], t["preset_b"]);
  json swappedPositions = trialsOfRow(p, std::size_t(row));
  const std::size_t i = random() % swappedPositions.size(), j = (i + 1 + random() % (swappedPositions.size() - 1)) % swappedPositions.size();
  std::swap(swappedPositions[i]["position"], swappedPositions[j]["position"]);
  for (const json& forged : {trialsOfRow(p, other), swappedAB, swappedPositions}) {
    const std::string refused = enrol(coordinator, p.id, "P0", p.groups[0], row, forged.dump());
    CHECK(refused.find("are not row " + std::to_string(row) + " of its counterbalancing") != std::string::npos);
    CHECK(studySnapshot(c.admin) == before);
  }
  // The drawn row's own trials are enrolled; the same row for a second participant is refused.
  CHECK(enrol(coordinator, p.id, "P0", p.groups[0], row, trialsOfRow(p, std::size_t(row)).dump()) == "enrolled");
  const std::string withOne = studySnapshot(c.admin);
  const std::string again = enrol(coordinator, p.id, "P1", p.groups[0], row, trialsOfRow(p, std::size_t(row)).dump());
  CHECK(again.find("is participant 'P0''s; draw a new one") != std::string::npos);
  CHECK(studySnapshot(c.admin) == withOne);
  // Through the program nothing changes for an honest laptop: it draws and sends the drawn row.
  for (int k = 1; k < 4; ++k) {
    auto part = enrolOrResume(coordinator, p, "P" + std::to_string(k), p.groups[std::size_t(k) % p.groups.size()]);
    REQUIRE_MESSAGE(part, (part ? "" : part.error().message));
  }
  MESSAGE("seed " << seed << ": drawn row " << row << ", another row " << other);
}

TEST_CASE("StudyChecks_ADemotedCoordinatorWritesNothingMoreToHerOwnStudies") {
  auto url = test::freshPostgresDatabase("the study checks test");
  if (!url) return;
  test::SecureClass c(*url);
  Database ada = test::openAt(c.coordinatorUrl);
  const quiz::StudyProtocol p = paperSurvey();
  REQUIRE(saveStudy(ada, p));
  auto first = enrolOrResume(ada, p, "P0", p.groups[0]);
  REQUIRE(first);
  // A second coordinator demotes ada to instructor (audited), as the class's coordinators may.
  const std::string ben = test::uniqueLogin("ben");
  const std::string benUrl = c.account(ada, ben, ClassRole::Coordinator);
  Database benDb = test::openAt(benUrl);
  REQUIRE(setMemberRole(benDb, c.code, "", c.coordinator, ClassRole::Instructor));

  const std::string before = studySnapshot(c.admin);
  const auto refusedAsDemoted = [&](const Status& s, const std::string& what) {
    CAPTURE(what);
    REQUIRE_FALSE(s);
    CAPTURE(s.error().message);
    // Refused by the server's check, or before it: demoted, she no longer reads the participant
    // she would write to (migration 24).
    CHECK((s.error().message.find("is no class's coordinator") != std::string::npos ||
           s.error().message.find("has no participant 'P0'") != std::string::npos));
    CHECK(studySnapshot(c.admin) == before);
  };
  quiz::StudyProtocol retitled = p;
  retitled.title += " (edited)";
  refusedAsDemoted(saveStudy(ada, retitled), "register");
  auto enrolled = enrolOrResume(ada, p, "P1", p.groups[0]);
  refusedAsDemoted(enrolled ? Status{} : Status(tl::unexpected(enrolled.error())), "enrol");
  auto resumed = enrolOrResume(ada, p, "P0", p.groups[0]);
  refusedAsDemoted(resumed ? Status{} : Status(tl::unexpected(resumed.error())), "resume");
  RatingRecord r;
  r.position = 0;
  r.item = p.items[0].id;
  r.ratingAsShown = 3;
  refusedAsDemoted(recordRating(ada, *first, r), "rate");
  refusedAsDemoted(recordTrialViewing(ada, *first, 0, 100, 100, 1, "", true), "viewing");
  refusedAsDemoted(markParticipantComplete(ada, *first), "complete");
  refusedAsDemoted(withdrawStudyParticipant(ada, p.id, "P0", StudyWithdrawalKind::Withdrawn, "asked to stop", std::nullopt),
                   "withdraw");
  for (const std::string& sql : {"SELECT at_draw_study_row('" + p.id + "')",
                                "SELECT at_set_study_owner('" + p.id + "', '" + ben + "')"}) {
    auto s = ada.exec(sql);
    refusedAsDemoted(s, sql);
  }
  // Made coordinator again, she writes again.
  REQUIRE(setMemberRole(benDb, c.code, "", c.coordinator, ClassRole::Coordinator));
  CHECK(recordRating(ada, *first, r));
}

TEST_CASE("StudyChecks_StudyMergeIntoTheServerIsTheCurrentCoordinatorsAlone_CheckedAndAudited") {
  auto url = test::freshPostgresDatabase("the study checks test");
  if (!url) return;
  test::SecureClass c(*url);
  const quiz::StudyProtocol p = paperSurvey();
  const std::uint64_t seed = test::freshSeed("StudyChecks_StudyMergeIntoTheServer");
  std::mt19937_64 random(seed);
  // Two lab machines without a server, each with its own participants, ratings and a withdrawal.
  test::TempDir dir;
  std::vector<Database> labs;
  int participants = 0;
  for (int m = 0; m < 2; ++m) {
    labs.push_back(test::openAt((dir.path() / ("lab" + std::to_string(m) + ".db")).string()));
    REQUIRE(saveStudy(labs.back(), p));
    const int here = 1 + int(random() % 3);
    for (int i = 0; i < here; ++i, ++participants) {
      auto part = enrolOrResume(labs.back(), p, "L" + std::to_string(m) + "P" + std::to_string(i),
                                p.groups[random() % p.groups.size()]);
      REQUIRE(part);
      for (const auto& t : part->trials) {
        RatingRecord r;
        r.position = t.position;
        r.item = p.items[random() % p.items.size()].id;
        r.ratingAsShown = 1 + int(random() % 5);
        REQUIRE(recordRating(labs.back(), *part, r));
      }
    }
    REQUIRE(withdrawStudyParticipant(labs.back(), p.id, "L" + std::to_string(m) + "P0", StudyWithdrawalKind::Withdrawn,
                                     "asked to stop", std::nullopt));
  }
  const std::vector<StudyMergeSource> sources = {{"lab0.db", &labs[0], nullptr}, {"lab1.db", &labs[1], nullptr}};

  // A student, the instructor: refused, nothing changes (the study is not even registered).
  const std::string before = studySnapshot(c.admin);
  for (const std::string& who : {c.samUrl, c.instructorUrl}) {
    Database db = test::openAt(who);
    auto merged = mergeStudy(db, sources, p.id);
    REQUIRE_FALSE(merged);
    CHECK(merged.error().message.find("is no class's coordinator") != std::string::npos);
    CHECK(studySnapshot(c.admin) == before);
  }
  // With raw SQL on her own connection, the student is refused as well.
  Database sam = test::openAt(c.samUrl);
  CHECK_FALSE(sam.exec("SELECT at_merge_participant('" + p.id + "', 'X1', '{\"participant\": {}, \"trials\": [], \"ratings\": []}', 'x')"));
  CHECK_FALSE(sam.exec("INSERT INTO study_participants (study_id, participant_id, group_name, enrolment_index) VALUES ('" +
                       p.id + "', 'X1', 'g', 0)"));
  CHECK(studySnapshot(c.admin) == before);

  // The coordinator: every participant once, with their withdrawal, each merge audited as hers.
  Database ada = test::openAt(c.coordinatorUrl);
  auto merged = mergeStudy(ada, sources, p.id);
  REQUIRE_MESSAGE(merged, (merged ? "" : merged.error().message));
  CHECK(merged->participants == participants);
  CHECK(merged->sources[0].added + merged->sources[1].added == participants);
  CHECK(merged->sources[0].withdrawals + merged->sources[1].withdrawals == 2);
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_audit WHERE action = 'study_merged' AND login = '" +
                                       c.coordinator + "'") == participants);
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM study_participants WHERE withdrawn_at IS NOT NULL") == 2);
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM study_ratings") ==
        test::scalarCount(labs[0], "SELECT COUNT(*) FROM study_ratings") +
            test::scalarCount(labs[1], "SELECT COUNT(*) FROM study_ratings"));
  const std::string once = studySnapshot(c.admin);
  auto again = mergeStudy(ada, sources, p.id);
  REQUIRE(again);
  CHECK(again->sources[0].alreadyThere + again->sources[1].alreadyThere == participants);
  CHECK(studySnapshot(c.admin) == once);

  // A participant recorded outside the study's design is refused whole.
  {
    auto s = c.admin.prepare("SELECT at_merge_participant(?1, 'BAD1', ?2, 'forged')");
    REQUIRE(s);
    const json forged = {{"participant", {{"group_name", p.groups[0]}, {"session", 1}, {"started_at", "2026-01-01T00:00:00.000Z"}}},
                         {"trials", json::array({{{"position", 0}, {"structure", "pancreas"}, {"a_condition", p.conditions[0].id},
                                                  {"b_condition", p.conditions[1].id}, {"preset_a", "x"}, {"preset_b", "y"},
                                                  {"toggles", 0}, {"viewing_measured", 1}}})},
                         {"ratings", json::array()}};
    s->bind(1, p.id).bind(2, forged.dump());
    auto done = s->step();
    REQUIRE_FALSE(done);
    CHECK(done.error().message.find("outside the study's design") != std::string::npos);
    CHECK(studySnapshot(c.admin) == once);
  }
  MESSAGE("seed " << seed << ": " << participants << " participants merged from 2 labs");
}
