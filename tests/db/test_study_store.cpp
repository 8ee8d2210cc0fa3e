#include <doctest/doctest.h>

#include <algorithm>
#include <latch>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/study_store.h"
#include "quiz/study_design.h"
#include "quiz/study_protocol.h"
#include "quiz/responses_long_reader.h"
#include "quiz/study_report.h"
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

TEST_CASE("StudyStore_RatingQuality_IsStoredExportedAndReplacedWithTheRating") {
  // The render quality a participant saw: stored with each rating, blank when not known,
  // replaced when the item is rated again.
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  const auto p = protocol();
  REQUIRE(db::saveStudy(*db, p).has_value());
  auto part = db::enrolOrResume(*db, p, "P0", "medical");
  REQUIRE(part.has_value());
  const auto& trial = part->trials.front();
  db::RatingRecord seen;
  seen.position = trial.position;
  seen.item = p.items[0].id;
  seen.ratingAsShown = 2;
  seen.qualityLevel = 3;
  seen.qualityFullLevel = 5;
  seen.qualityScale = 0.25;
  seen.settleMs = 2100;
  REQUIRE(db::recordRating(*db, *part, seen).has_value());
  db::RatingRecord unknown;
  unknown.position = trial.position;
  unknown.item = p.items[1].id;
  unknown.ratingAsShown = 4;
  REQUIRE(db::recordRating(*db, *part, unknown).has_value());
  auto rows = db::studyResponseRows(*db, p);
  REQUIRE(rows.has_value());
  REQUIRE(rows->size() == 2);
  CHECK((*rows)[0].qualityLevel == 3);
  CHECK((*rows)[0].qualityFullLevel == 5);
  CHECK((*rows)[0].qualityScale == doctest::Approx(0.25));
  CHECK((*rows)[0].settleMs == doctest::Approx(2100));
  CHECK_FALSE((*rows)[1].qualityLevel.has_value());
  CHECK_FALSE((*rows)[1].settleMs.has_value());
  // The long table carries them; unknown ones are blank.
  const auto csv = quiz::parseCsv(quiz::responsesLongCsv(*rows));
  REQUIRE(csv.size() == 3);
  const auto col = [&](const std::string& name) {
    const auto it = std::find(csv[0].begin(), csv[0].end(), name);
    REQUIRE(it != csv[0].end());
    return std::size_t(it - csv[0].begin());
  };
  CHECK(csv[1][col("quality_level")] == "3");
  CHECK(csv[1][col("quality_full_level")] == "5");
  CHECK(csv[1][col("quality_scale")] == "0.25");
  CHECK(csv[1][col("settle_ms")] == "2100");
  CHECK(csv[2][col("quality_level")].empty());
  CHECK(csv[2][col("settle_ms")].empty());
  // Rated again at full quality: the new quality replaces the old.
  seen.qualityLevel = 5;
  seen.settleMs = 900;
  REQUIRE(db::recordRating(*db, *part, seen).has_value());
  rows = db::studyResponseRows(*db, p);
  REQUIRE(rows.has_value());
  CHECK((*rows)[0].qualityLevel == 5);
  CHECK((*rows)[0].settleMs == doctest::Approx(900));
}

TEST_CASE("StudyStore_ResumedParticipant_EachRatingKeepsTheSessionItWasGivenIn") {
  test::TempDir dir;
  auto db = db::Database::open(test::freshDatabase(dir, "t.db"));
  REQUIRE(db.has_value());
  const auto p = protocol();
  REQUIRE(db::saveStudy(*db, p).has_value());
  auto first = db::enrolOrResume(*db, p, "P0", "medical");
  REQUIRE(first.has_value());
  db::RatingRecord r;
  r.item = p.items[0].id;
  r.ratingAsShown = 2;
  REQUIRE(db::recordRating(*db, *first, r).has_value());
  REQUIRE(db::recordTrialViewing(*db, *first, 0, 100, 200, 1, "", false).has_value());
  auto second = db::enrolOrResume(*db, p, "P0", "medical");  // session 2
  REQUIRE(second.has_value());
  r.item = p.items[1].id;
  REQUIRE(db::recordRating(*db, *second, r).has_value());
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

namespace {

// A simulated participant's opinion on the paper's scale (1 = prefer WDT … 5 = prefer bare),
// fixed by who they are, not by the order or the machine they happen to get.
int opinion(int participant, std::size_t structure, std::size_t item) {
  const int v = int((std::size_t(participant) * 7 + structure * 3 + item * 5) % 5) + 1;
  return participant % 3 == 0 ? std::max(1, v - 2) : v;  // a third lean towards WDT
}

// Runs one participant from enrolment to completion on `db`, rating every item of every trial
// with `opinion` (converted to the blinded A/B scale of the trial shown). Empty or an error.
std::string runParticipant(db::Database& db, const quiz::StudyProtocol& p, int participant) {
  const std::string id = "P" + std::to_string(participant);
  auto part = db::enrolOrResume(db, p, id, p.groups[std::size_t(participant) % p.groups.size()]);
  if (!part) return id + ": " + part.error().message;
  for (const auto& t : part->trials) {
    const std::size_t s = std::size_t(std::find(p.structures.begin(), p.structures.end(), t.structure) - p.structures.begin());
    const bool aIsWdt = t.aCondition == p.conditions[0].id;
    for (std::size_t i = 0; i < p.items.size(); ++i) {
      db::RatingRecord r;
      r.position = t.position;
      r.item = p.items[i].id;
      for (int shown = 1; shown <= 5; ++shown)
        if (quiz::unblindRating(shown, aIsWdt, p.scale) == opinion(participant, s, i)) r.ratingAsShown = shown;
      r.responseMs = 900;
      if (auto st = db::recordRating(db, *part, r); !st) return id + ": " + st.error().message;
    }
    if (auto st = db::recordTrialViewing(db, *part, t.position, 3000, 2500, 2, ""); !st)
      return id + ": " + st.error().message;
  }
  if (auto st = db::markParticipantComplete(db, *part); !st) return id + ": " + st.error().message;
  return {};
}

// Participants 0 … count−1 run one after another on one machine's fresh database.
db::Database oneMachine(const test::TempDir& dir, const quiz::StudyProtocol& p, int count) {
  auto db = db::Database::open(test::freshDatabase(dir, "one_machine.db"));
  REQUIRE(db.has_value());
  REQUIRE(db::saveStudy(*db, p).has_value());
  for (int who = 0; who < count; ++who) REQUIRE(runParticipant(*db, p, who).empty());
  return std::move(*db);
}

// Each participant's plan as the export shows it: structure → (1-based order, condition shown as A).
using PlanSeen = std::map<std::string, std::pair<int, std::string>>;
std::map<std::string, PlanSeen> plansSeen(const std::vector<quiz::StudyResponseRow>& rows) {
  std::map<std::string, PlanSeen> out;
  for (const auto& r : rows) out[r.participantId][r.structure] = {r.presentationOrder, r.aCondition};
  return out;
}

}  // namespace

TEST_CASE("StudyStore_ThreeLabMachinesAtOnce_EveryCounterbalancingRowOnce_SummaryAsOnOneMachine") {
  // 19 participants × 13 structures, enrolled and rated from three connections at once (three lab
  // machines on one class server; on SQLite three connections to one file). Enrolment draws the
  // counterbalancing row from the shared store, so the study is as balanced as on one machine and
  // its summary is the one machine's.
  test::TempDir dir;
  const auto p = protocol(11);
  REQUIRE(p.structures.size() == 13);
  const int participants = 19, machines = 3;
  const std::string shared = test::freshDatabase(dir, "class.db");
  {
    auto db = db::Database::open(shared);
    REQUIRE(db.has_value());
    REQUIRE(db::saveStudy(*db, p).has_value());
  }
  std::vector<std::string> errors;
  std::mutex errorsMutex;
  std::latch start(machines);
  std::vector<std::thread> lab;
  for (int m = 0; m < machines; ++m) {
    lab.emplace_back([&, m] {
      auto db = db::Database::open(shared);
      start.arrive_and_wait();
      std::string error = db ? "" : db.error().message;
      for (int who = m; who < participants && error.empty(); who += machines) error = runParticipant(*db, p, who);
      if (!error.empty()) {
        std::lock_guard lock(errorsMutex);
        errors.push_back("machine " + std::to_string(m) + ": " + error);
      }
    });
  }
  for (auto& t : lab) t.join();
  CHECK(errors.empty());
  for (const auto& e : errors) MESSAGE(e);

  auto server = db::Database::open(shared);
  REQUIRE(server.has_value());
  auto enrolled = db::studyParticipantRows(*server, p.id);
  REQUIRE(enrolled.has_value());
  REQUIRE(enrolled->size() == std::size_t(participants));
  std::set<int> rows;
  for (const auto& e : *enrolled) {
    rows.insert(e.enrolmentIndex);
    CHECK(e.complete);
    CHECK(e.sessions == 1);
  }
  CHECK(rows.size() == std::size_t(participants));  // no counterbalancing row given twice …
  CHECK(*rows.begin() == 0);
  CHECK(*rows.rbegin() == participants - 1);        // … and none skipped
  auto serverRows = db::studyResponseRows(*server, p);
  REQUIRE(serverRows.has_value());
  CHECK(serverRows->size() == std::size_t(participants) * p.structures.size() * p.items.size());
  // Every participant got the plan of their enrolment row.
  const auto seen = plansSeen(*serverRows);
  for (const auto& e : *enrolled) {
    CAPTURE(e.participantId);
    PlanSeen planned;
    for (const auto& t : quiz::planParticipant(p.structures.size(), std::size_t(e.enrolmentIndex), p.seed))
      planned[p.structures[t.structureIndex]] = {int(t.position) + 1,
                                                 p.conditions[t.aIsFirstCondition ? 0 : 1].id};
    CHECK(seen.at(e.participantId) == planned);
  }

  // The same participants one after another on one machine.
  test::TempDir alone;
  auto single = oneMachine(alone, p, participants);
  auto singleRows = db::studyResponseRows(single, p);
  REQUIRE(singleRows.has_value());
  // Balance: the same rows of the design were used, so each structure was shown at each position
  // and as A under WDT as often as on one machine.
  std::map<std::pair<std::string, int>, int> atPosition[2];
  std::map<std::string, int> wdtAsA[2];
  for (int k = 0; k < 2; ++k)
    for (const auto& [who, plan] : plansSeen(k == 0 ? *serverRows : *singleRows))
      for (const auto& [structure, shown] : plan) {
        ++atPosition[k][{structure, shown.first}];
        wdtAsA[k][structure] += shown.second == p.conditions[0].id;
      }
  CHECK(atPosition[0] == atPosition[1]);
  CHECK(wdtAsA[0] == wdtAsA[1]);
  const auto summaryOf = [&](const std::vector<quiz::StudyResponseRow>& r) {
    return quiz::summaryCsv(quiz::summariseStudy(p, r));
  };
  CHECK(summaryOf(*serverRows) == summaryOf(*singleRows));
  const auto summary = quiz::summariseStudy(p, *serverRows);
  CHECK(summary.at(0, summary.columns.size() - 1).stats.n == std::size_t(participants));
}

namespace {

// The long table's lines without its header, sorted: the same records whatever the order.
std::vector<std::string> sortedRecords(const std::vector<quiz::StudyResponseRow>& rows) {
  std::stringstream csv(quiz::responsesLongCsv(rows));
  std::vector<std::string> lines;
  std::string line;
  std::getline(csv, line);  // header
  while (std::getline(csv, line)) lines.push_back(line);
  std::sort(lines.begin(), lines.end());
  return lines;
}

// `machines` lab databases, participant k on machine k mod machines (each machine enrolling from
// design row 0), and every lab's rows as exported.
struct LabMachines {
  std::vector<db::Database> labs;
  std::vector<quiz::StudyResponseRow> everyLabsRows;
};
LabMachines runOnLabs(const test::TempDir& dir, const quiz::StudyProtocol& p, int participants, int machines) {
  LabMachines out;
  for (int m = 0; m < machines; ++m) {
    auto lab = db::Database::open(test::freshDatabase(dir, "lab" + std::to_string(m) + ".db"));
    REQUIRE(lab.has_value());
    REQUIRE(db::saveStudy(*lab, p).has_value());
    for (int who = m; who < participants; who += machines) REQUIRE(runParticipant(*lab, p, who).empty());
    auto rows = db::studyResponseRows(*lab, p);
    REQUIRE(rows.has_value());
    out.everyLabsRows.insert(out.everyLabsRows.end(), rows->begin(), rows->end());
    out.labs.push_back(std::move(*lab));
  }
  return out;
}

}  // namespace

TEST_CASE("StudyStore_MergeThreeMachinesWithoutServer_EveryRecordOnceSummaryAsOnOneMachineMergingAgainChangesNothing") {
  test::TempDir dir;
  const auto p = protocol(11);
  const int participants = 19, machines = 3;
  auto [labs, everyLabsRows] = runOnLabs(dir, p, participants, machines);
  std::vector<db::StudyMergeSource> sources;
  for (int m = 0; m < machines; ++m) sources.push_back({"lab" + std::to_string(m), &labs[std::size_t(m)]});
  auto merged = db::Database::open(test::freshDatabase(dir, "merged.db"));
  REQUIRE(merged.has_value());

  auto report = db::mergeStudy(*merged, sources, p.id);
  REQUIRE_MESSAGE(report.has_value(), report.error().message);
  REQUIRE(report->sources.size() == 3);
  CHECK(report->sources[0].added == 7);
  CHECK(report->sources[1].added == 6);
  CHECK(report->sources[2].added == 6);
  CHECK(report->participants == participants);
  CHECK(report->offDesign.empty());
  // Each machine started at design row 0: rows 0–5 three times, row 6 once, rows 7–25 never.
  CHECK(report->cycle == 26);
  CHECK(report->designRows == std::map<std::size_t, int>{{0, 3}, {1, 3}, {2, 3}, {3, 3}, {4, 3}, {5, 3}, {6, 1}});
  CHECK_FALSE(report->balanced());

  auto mergedRows = db::studyResponseRows(*merged, p);
  REQUIRE(mergedRows.has_value());
  CHECK(sortedRecords(*mergedRows) == sortedRecords(everyLabsRows));  // every record once, as recorded
  auto enrolled = db::studyParticipantRows(*merged, p.id);
  REQUIRE(enrolled.has_value());
  std::set<int> indices;
  for (const auto& e : *enrolled) indices.insert(e.enrolmentIndex);
  CHECK(indices.size() == std::size_t(participants));
  // The summary is the one machine's (each simulated participant's opinions are their own).
  test::TempDir alone;
  auto single = oneMachine(alone, p, participants);
  auto singleRows = db::studyResponseRows(single, p);
  REQUIRE(singleRows.has_value());
  CHECK(quiz::summaryCsv(quiz::summariseStudy(p, *mergedRows)) == quiz::summaryCsv(quiz::summariseStudy(p, *singleRows)));
  // A single machine's enrolment is balanced by the same report.
  auto copy = db::Database::open(test::freshDatabase(alone, "copy.db"));
  REQUIRE(copy.has_value());
  auto one = db::mergeStudy(*copy, {{"one", &single}}, p.id);
  REQUIRE(one.has_value());
  CHECK(one->balanced());

  auto again = db::mergeStudy(*merged, sources, p.id);
  REQUIRE(again.has_value());
  CHECK(again->sources[0].added + again->sources[1].added + again->sources[2].added == 0);
  CHECK(again->sources[0].alreadyThere == 7);
  CHECK(again->participants == participants);
  auto rowsAgain = db::studyResponseRows(*merged, p);
  REQUIRE(rowsAgain.has_value());
  CHECK(rowsAgain->size() == mergedRows->size());
}

namespace {

// A lab machine's export bundle as `study merge` reads it: the long table written and read back.
std::vector<quiz::StudyResponseRow> exportedRows(db::Database& lab, const quiz::StudyProtocol& p) {
  auto rows = db::studyResponseRows(lab, p);
  REQUIRE(rows.has_value());
  auto read = quiz::readResponsesLongCsv(quiz::responsesLongCsv(*rows), "responses_long.csv", p);
  REQUIRE_MESSAGE(read.has_value(), read.error().message);
  return std::move(*read);
}

}  // namespace

TEST_CASE("StudyStore_MergeThreeMachinesExportBundles_SummaryAsOnOneMachineAgainNothingConflictsWriteNothing") {
  test::TempDir dir;
  const auto p = protocol(11);
  REQUIRE(p.structures.size() == 13);
  const int participants = 19, machines = 3;
  auto [labs, everyLabsRows] = runOnLabs(dir, p, participants, machines);
  std::vector<std::vector<quiz::StudyResponseRow>> bundles;
  for (auto& lab : labs) bundles.push_back(exportedRows(lab, p));
  std::vector<db::StudyMergeSource> sources;
  for (int m = 0; m < machines; ++m)
    sources.push_back({"lab" + std::to_string(m) + "/", nullptr, &bundles[std::size_t(m)]});
  auto merged = db::Database::open(test::freshDatabase(dir, "merged.db"));
  REQUIRE(merged.has_value());

  auto withoutDesign = db::mergeStudy(*merged, sources, p.id);
  REQUIRE_FALSE(withoutDesign.has_value());  // a bundle is read against the study's design
  auto report = db::mergeStudy(*merged, sources, p.id, &p);
  REQUIRE_MESSAGE(report.has_value(), report.error().message);
  CHECK(report->sources[0].added == 7);
  CHECK(report->sources[1].added == 6);
  CHECK(report->sources[2].added == 6);
  CHECK(report->participants == participants);
  CHECK(report->offDesign.empty());
  CHECK(report->designRows == std::map<std::size_t, int>{{0, 3}, {1, 3}, {2, 3}, {3, 3}, {4, 3}, {5, 3}, {6, 1}});
  auto mergedRows = db::studyResponseRows(*merged, p);
  REQUIRE(mergedRows.has_value());
  CHECK(mergedRows->size() == std::size_t(participants) * 13 * p.items.size());
  CHECK(sortedRecords(*mergedRows) == sortedRecords(everyLabsRows));  // the export of the merge: every record once
  test::TempDir alone;
  auto single = oneMachine(alone, p, participants);
  auto singleRows = db::studyResponseRows(single, p);
  REQUIRE(singleRows.has_value());
  CHECK(quiz::summaryCsv(quiz::summariseStudy(p, *mergedRows)) == quiz::summaryCsv(quiz::summariseStudy(p, *singleRows)));
  const auto completion = db::studyCompletion(*merged, p.id);
  REQUIRE(completion.has_value());
  for (const auto& c : *completion) CHECK(c.complete);

  // Again, and the lab databases the bundles came from: nothing changes.
  auto again = db::mergeStudy(*merged, sources, p.id, &p);
  REQUIRE_MESSAGE(again.has_value(), again.error().message);
  CHECK(again->sources[0].added + again->sources[1].added + again->sources[2].added == 0);
  CHECK(again->sources[0].alreadyThere + again->sources[1].alreadyThere + again->sources[2].alreadyThere == participants);
  std::vector<db::StudyMergeSource> databases;
  for (int m = 0; m < machines; ++m) databases.push_back({"lab" + std::to_string(m) + ".db", &labs[std::size_t(m)]});
  auto fromDatabases = db::mergeStudy(*merged, databases, p.id);
  REQUIRE_MESSAGE(fromDatabases.has_value(), fromDatabases.error().message);
  CHECK(fromDatabases->sources[0].added + fromDatabases->sources[1].added + fromDatabases->sources[2].added == 0);
  auto rowsAgain = db::studyResponseRows(*merged, p);
  REQUIRE(rowsAgain.has_value());
  CHECK(quiz::responsesLongCsv(*rowsAgain) == quiz::responsesLongCsv(*mergedRows));

  // A bundle whose P4 rated otherwise (another person under that id): refused, nothing written,
  // although two good bundles come first.
  auto clashing = bundles[1];
  auto changed = std::find_if(clashing.begin(), clashing.end(), [](const auto& r) { return r.participantId == "P4"; });
  REQUIRE(changed != clashing.end());
  changed->ratingAb = changed->ratingAb == 1 ? 2 : 1;
  changed->rating = quiz::unblindRating(changed->ratingAb, changed->aCondition == p.conditions[0].id, p.scale);
  auto fresh = db::Database::open(test::freshDatabase(dir, "fresh.db"));
  REQUIRE(fresh.has_value());
  auto clash = db::mergeStudy(*fresh, {sources[0], sources[1], {"other/", nullptr, &clashing}}, p.id, &p);
  REQUIRE_FALSE(clash.has_value());
  CHECK((clash.error().kind == ErrorKind::Conflict));
  CHECK(clash.error().message.find("'P4' of other/ is also in lab1/") != std::string::npos);
  auto nothing = db::studyParticipantRows(*fresh, p.id);
  REQUIRE(nothing.has_value());
  CHECK(nothing->empty());
  auto clashMerged = db::mergeStudy(*merged, {{"other/", nullptr, &clashing}}, p.id, &p);
  REQUIRE_FALSE(clashMerged.has_value());
  auto unchanged = db::studyResponseRows(*merged, p);
  REQUIRE(unchanged.has_value());
  CHECK(quiz::responsesLongCsv(*unchanged) == quiz::responsesLongCsv(*mergedRows));

  // A partial participant's bundle (some trials rated) merges and counts for their design row.
  auto partial = db::Database::open(test::freshDatabase(dir, "partial.db"));
  REQUIRE(partial.has_value());
  REQUIRE(db::saveStudy(*partial, p).has_value());
  auto q = db::enrolOrResume(*partial, p, "Q1", p.groups[0]);
  REQUIRE(q.has_value());
  for (int position : {0, 1})
    for (const auto& item : p.items) {
      db::RatingRecord r;
      r.position = position;
      r.item = item.id;
      r.ratingAsShown = 4;
      REQUIRE(db::recordRating(*partial, *q, r).has_value());
    }
  auto partialRows = exportedRows(*partial, p);
  auto withPartial = db::mergeStudy(*merged, {{"partial/", nullptr, &partialRows}}, p.id, &p);
  REQUIRE_MESSAGE(withPartial.has_value(), withPartial.error().message);
  CHECK(withPartial->sources[0].added == 1);
  CHECK(withPartial->offDesign.empty());
  CHECK(withPartial->designRows.at(0) == 4);
  auto status = db::studyCompletion(*merged, p.id);
  REQUIRE(status.has_value());
  CHECK_FALSE(status->back().complete);
  CHECK(status->back().ratingsGiven == 2 * int(p.items.size()));
}

TEST_CASE("StudyStore_MergeConflicts_SameIdOtherRecordsOrOtherDesign_WriteNothing") {
  test::TempDir dir;
  const auto p = protocol(11);
  auto open = [&](const std::string& name) {
    auto db = db::Database::open(test::freshDatabase(dir, name));
    REQUIRE(db.has_value());
    return std::move(*db);
  };
  db::Database a = open("a.db"), b = open("b.db"), target = open("target.db");
  REQUIRE(db::saveStudy(a, p).has_value());
  REQUIRE(db::saveStudy(b, p).has_value());
  REQUIRE(runParticipant(a, p, 0).empty());
  REQUIRE(runParticipant(a, p, 1).empty());
  REQUIRE(runParticipant(b, p, 2).empty());
  REQUIRE(runParticipant(b, p, 4).empty());  // b's participant P4 …
  // … and another person enrolled as P4 on machine c, rating otherwise.
  db::Database c = open("c2.db");
  REQUIRE(db::saveStudy(c, p).has_value());
  auto otherP4 = db::enrolOrResume(c, p, "P4", p.groups[0]);
  REQUIRE(otherP4.has_value());
  db::RatingRecord r;
  r.item = p.items[0].id;
  r.ratingAsShown = 3;
  REQUIRE(db::recordRating(c, *otherP4, r).has_value());

  auto clash = db::mergeStudy(target, {{"a", &a}, {"b", &b}, {"c", &c}}, p.id);
  REQUIRE_FALSE(clash.has_value());
  CHECK((clash.error().kind == ErrorKind::Conflict));
  CHECK(clash.error().message.find("'P4' of c is also in b") != std::string::npos);
  auto nothing = db::studyParticipantRows(target, p.id);
  REQUIRE(nothing.has_value());
  CHECK(nothing->empty());  // all or nothing: a and b were not merged either

  auto otherDesign = p;
  otherDesign.seed = 12;
  db::Database d = open("d.db");
  REQUIRE(db::saveStudy(d, otherDesign).has_value());
  auto mismatch = db::mergeStudy(target, {{"a", &a}, {"d", &d}}, p.id);
  REQUIRE_FALSE(mismatch.has_value());
  CHECK(mismatch.error().message.find("d: study") != std::string::npos);
  auto missing = db::mergeStudy(target, {{"a", &a}}, "no_such_study");
  REQUIRE_FALSE(missing.has_value());
  CHECK((missing.error().kind == ErrorKind::NotFound));
}

TEST_CASE("StudyStore_UnmeasuredViewingTimes_StoredBlankNotZero_OldZerosMigrateToBlank") {
  test::TempDir dir;
  const std::string path = test::freshDatabase(dir, "views.db");
  const auto p = protocol();
  const auto blankTrials = [](db::Database& d) {
    auto s = d.prepare("SELECT COUNT(*) FROM study_trials WHERE view_ms_a IS NULL AND view_ms_b IS NULL");
    REQUIRE(s.has_value());
    REQUIRE(*s->step());
    return s->int64(0);
  };
  {
    db::OpenOptions options;
    options.targetVersion = 13;  // before blank viewing times: unmeasured ones were stored as 0
    auto old = db::Database::open(path, options);
    REQUIRE(old.has_value());
    REQUIRE(db::saveStudy(*old, p).has_value());
    // P0 enrolled as the program of that version did (row 0 of the counterbalancing square).
    REQUIRE(old->exec("INSERT INTO study_participants (study_id, participant_id, group_name, enrolment_index)"
                      " VALUES ('" + p.id + "', 'P0', 'medical', 0)"));
    for (const quiz::TrialPlan& plan : quiz::planParticipant(p.structures.size(), 0, p.seed)) {
      const std::string& structure = p.structures[plan.structureIndex];
      const int a = plan.aIsFirstCondition ? 0 : 1;
      REQUIRE(old->exec("INSERT INTO study_trials (study_id, participant_id, position, structure, a_condition, b_condition,"
                        " preset_a, preset_b) VALUES ('" + p.id + "', 'P0', " + std::to_string(plan.position) + ", '" +
                        structure + "', '" + p.conditions[std::size_t(a)].id + "', '" +
                        p.conditions[std::size_t(1 - a)].id + "', '" + p.presetFor(structure, a) + "', '" +
                        p.presetFor(structure, 1 - a) + "')"));
    }
    // As the program before it wrote them: trial 0 unmeasured as 0, trial 1 measured, looked 0 ms.
    REQUIRE(old->exec("UPDATE study_trials SET view_ms_a = 0, view_ms_b = 0, toggles = 0, viewing_measured = 0"
                      " WHERE position = 0").has_value());
    REQUIRE(old->exec("UPDATE study_trials SET view_ms_a = 0, view_ms_b = 0, viewing_measured = 1"
                      " WHERE position = 1").has_value());
    CHECK(blankTrials(*old) == 0);
  }
  auto db = db::Database::open(path);
  REQUIRE(db.has_value());
  // The migrated unmeasured trial is blank; the measured 0 stays 0; untouched trials keep 0.
  CHECK(blankTrials(*db) == 1);
  auto part = db::enrolOrResume(*db, p, "P0", "medical");
  REQUIRE(part.has_value());
  CHECK_FALSE(part->trials[0].viewingMeasured);
  CHECK(part->trials[1].viewingMeasured);
  REQUIRE(db::recordTrialViewing(*db, *part, 2, 100, 200, 1, "", false).has_value());
  CHECK(blankTrials(*db) == 2);
  REQUIRE(db::recordTrialViewing(*db, *part, 2, 150, 250, 2, "", true).has_value());
  CHECK(blankTrials(*db) == 1);
  auto trials = db::enrolOrResume(*db, p, "P0", "medical");
  REQUIRE(trials.has_value());
  CHECK(trials->trials[2].viewMsA == 150);
}
