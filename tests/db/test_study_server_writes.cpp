// A study on a class server is written only through the server's audited functions: the coordinator
// who registers it (with her own login) enrols its participants and records their ratings; a student,
// an instructor or another coordinator — through the program or with raw SQL on their own
// connection — changes nothing of it (the study tables and the audit stay byte-identical) and reads
// nothing of it (no participant's A/B key).
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/study_store.h"
#include "db/study_withdrawal.h"
#include "quiz/study_protocol.h"
#include "quiz/study_report.h"
#include "secure_class.h"
#include "study_server_snapshot.h"
#include "test_support.h"

using namespace at;
using namespace at::db;
namespace fs = std::filesystem;

namespace {

using test::paperSurvey;
using test::studySnapshot;

std::string sqlText(const std::string& s) { return "'" + s + "'"; }

}  // namespace

TEST_CASE("StudyServer_ACoordinatorLoginRegistersAndRunsAStudy_NoOtherLoginWritesOrReadsIt_RefusalsChangeNothing") {
  auto url = test::freshPostgresDatabase("the study-on-the-server test");
  if (!url) return;
  test::SecureClass c(*url);
  Database coordinator = test::openAt(c.coordinatorUrl);
  const std::string rival = test::uniqueLogin("bob");  // a coordinator too, but not the study's
  const std::string rivalUrl = c.account(coordinator, rival, ClassRole::Coordinator);
  Database bob = test::openAt(rivalUrl);
  Database sam = test::openAt(c.samUrl);
  Database instructor = test::openAt(c.instructorUrl);
  const std::uint64_t seed = test::freshSeed("StudyServer_CoordinatorLogin");
  std::mt19937 random{unsigned(seed)};

  // The coordinator, as herself: registers the study (it becomes hers), enrols and rates.
  const quiz::StudyProtocol p = paperSurvey();
  auto stored = saveStudy(coordinator, p);
  REQUIRE_MESSAGE(stored, (stored ? "" : stored.error().message));
  CHECK(studyOwner(c.admin, p.id) == c.coordinator);
  const int participants = 2 + int(random() % 3);
  std::vector<StudyParticipant> enrolled;
  std::map<std::string, int> given;  // "participant position item" → rating as shown
  for (int i = 0; i < participants; ++i) {
    auto part = enrolOrResume(coordinator, p, "P" + std::to_string(i), p.groups[std::size_t(i) % p.groups.size()]);
    REQUIRE_MESSAGE(part, (part ? "" : part.error().message));
    CHECK(part->enrolmentIndex == i);
    for (const auto& t : part->trials) {
      for (const auto& item : p.items) {
        RatingRecord r;
        r.position = t.position;
        r.item = item.id;
        r.ratingAsShown = 1 + int(random() % 5);
        REQUIRE(recordRating(coordinator, *part, r));
        given[part->participantId + " " + std::to_string(t.position) + " " + item.id] = r.ratingAsShown;
      }
      REQUIRE(recordTrialViewing(coordinator, *part, t.position, 1000.0 + t.position, 900.0, 2, "", true));
    }
    REQUIRE(markParticipantComplete(coordinator, *part));
    enrolled.push_back(*part);
  }
  // What she recorded is what the server holds, unblinded for her (the owner) only.
  auto rows = studyResponseRows(coordinator, p);
  REQUIRE_MESSAGE(rows, (rows ? "" : rows.error().message));
  CHECK(rows->size() == given.size());
  for (const auto& r : *rows)
    CHECK(given.at(r.participantId + " " + std::to_string(r.presentationOrder - 1) + " " + r.item) == r.ratingAb);
  auto done = studyCompletion(coordinator, p.id);
  REQUIRE(done);
  for (const auto& d : *done) CHECK(d.complete);
  CHECK(test::scalarCount(coordinator, "SELECT COUNT(*) FROM class_audit WHERE action = 'study_registered' AND login = " +
                                           sqlText(c.coordinator) + " AND target = " + sqlText(p.id)) == 1);
  // A rating she changes is a correction: audited with the old and the new value.
  {
    const StudyParticipant& first = enrolled.front();
    const std::string key = first.participantId + " 0 " + p.items[0].id;
    RatingRecord r;
    r.position = 0;
    r.item = p.items[0].id;
    r.ratingAsShown = given[key] % 5 + 1;
    REQUIRE(recordRating(coordinator, first, r));
    CHECK(test::scalarCount(coordinator, "SELECT COUNT(*) FROM class_audit WHERE action = 'study_rerated' AND old_value = '" +
                                             std::to_string(given[key]) + "' AND new_value = '" +
                                             std::to_string(r.ratingAsShown) + "'") == 1);
    given[key] = r.ratingAsShown;
  }

  // Nobody else reads a row of it: not the A/B keys (study_trials), not the ratings.
  for (Database* other : {&sam, &instructor, &bob})
    for (const char* table : {"studies", "study_participants", "study_trials", "study_ratings"})
      CHECK(test::scalarCount(*other, std::string("SELECT COUNT(*) FROM ") + table) == 0);
  CHECK(test::scalarCount(sam, "SELECT COUNT(*) FROM class_audit") == 0);

  // Every attack, by each other login, through the program and with raw SQL (random order, seed
  // printed): refused, and the study tables and the audit stay byte-identical.
  const std::string before = studySnapshot(c.admin);
  const StudyParticipant victim = enrolled[random() % enrolled.size()];
  quiz::StudyProtocol changed = p;
  changed.title = "taken over";
  quiz::StudyProtocol own = p;
  own.id = "students_own_study";
  RatingRecord flip;
  flip.position = 0;
  flip.item = p.items[0].id;
  flip.ratingAsShown = 5;
  const std::string st = sqlText(p.id), who = sqlText(victim.participantId), session = std::to_string(victim.session);
  using Attack = std::function<bool(Database&, const std::string& login)>;
  const std::vector<std::pair<std::string, Attack>> attacks = {
      {"register over the study", [&](Database& d, const std::string&) { return bool(saveStudy(d, changed)); }},
      {"register an own study", [&](Database& d, const std::string&) { return bool(saveStudy(d, own)); }},
      {"take the study", [&](Database& d, const std::string& login) { return bool(setStudyOwner(d, p.id, login)); }},
      {"enrol", [&](Database& d, const std::string&) { return bool(enrolOrResume(d, p, "P99", p.groups[0])); }},
      {"resume a participant", [&](Database& d, const std::string&) { return bool(enrolOrResume(d, p, victim.participantId, victim.group)); }},
      {"flip a rating", [&](Database& d, const std::string&) { return bool(recordRating(d, victim, flip)); }},
      {"change viewing", [&](Database& d, const std::string&) { return bool(recordTrialViewing(d, victim, 0, 1, 1, 0, "x", true)); }},
      {"complete", [&](Database& d, const std::string&) { return bool(markParticipantComplete(d, victim)); }},
      {"withdraw", [&](Database& d, const std::string&) {
         return bool(withdrawStudyParticipant(d, p.id, victim.participantId, StudyWithdrawalKind::Excluded, "spite", std::nullopt)); }},
      {"sql register", [&](Database& d, const std::string& login) {
         return bool(d.exec("SELECT at_register_study(" + st + ", 'x', 'phantom', 1, '{}', " + sqlText(login) + ")")); }},
      {"sql owner", [&](Database& d, const std::string& login) { return bool(d.exec("SELECT at_set_study_owner(" + st + ", " + sqlText(login) + ")")); }},
      {"sql draw", [&](Database& d, const std::string&) { return bool(d.exec("SELECT at_draw_study_row(" + st + ")")); }},
      {"sql enrol", [&](Database& d, const std::string&) {
         return bool(d.exec("SELECT at_enrol_participant(" + st + ", " + who + ", " + sqlText(victim.group) + ", NULL, '[]')")); }},
      {"sql rate", [&](Database& d, const std::string&) {
         return bool(d.exec("SELECT at_record_rating(" + st + ", " + who + ", " + session + ", 0, 'shape', 5, 0, 0, 0, 0, '', NULL, NULL, NULL, NULL)")); }},
      {"sql viewing", [&](Database& d, const std::string&) {
         return bool(d.exec("SELECT at_record_trial_viewing(" + st + ", " + who + ", " + session + ", 0, 1, 1, 0, 'x', 1)")); }},
      {"sql complete", [&](Database& d, const std::string&) { return bool(d.exec("SELECT at_complete_participant(" + st + ", " + who + ", " + session + ")")); }},
      {"sql withdraw", [&](Database& d, const std::string&) {
         return bool(d.exec("SELECT at_withdraw_participant(" + st + ", " + who + ", 'excluded', 'spite', '')")); }},
      {"sql insert rating", [&](Database& d, const std::string&) {
         return bool(d.exec("INSERT INTO study_ratings (study_id, participant_id, position, item, rating_ab) VALUES (" + st + ", " + who + ", 0, 'x', 5)")); }},
      {"sql update ratings", [&](Database& d, const std::string&) { return bool(d.exec("UPDATE study_ratings SET rating_ab = 6 - rating_ab")); }},
      {"sql unblind", [&](Database& d, const std::string&) { return bool(d.exec("UPDATE study_trials SET a_condition = b_condition")); }},
      {"sql owner column", [&](Database& d, const std::string& login) { return bool(d.exec("UPDATE studies SET owner = " + sqlText(login))); }},
      {"sql delete", [&](Database& d, const std::string&) { return bool(d.exec("DELETE FROM study_participants")); }},
      {"sql truncate", [&](Database& d, const std::string&) { return bool(d.exec("TRUNCATE study_ratings")); }},
      {"sql drop", [&](Database& d, const std::string&) { return bool(d.exec("DROP TABLE study_trials CASCADE")); }},
      {"sql audit", [&](Database& d, const std::string& login) {
         return bool(d.exec("SELECT at_audit(" + sqlText(login) + ", 'study_registered', '', " + st + ", NULL, NULL, '')")); }},
  };
  std::vector<std::size_t> order(attacks.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  for (auto [d, login] : {std::pair<Database*, std::string>{&sam, c.sam}, {&instructor, c.instructor}, {&bob, rival}}) {
    std::shuffle(order.begin(), order.end(), random);
    for (std::size_t i : order) {
      CAPTURE(login);
      CAPTURE(attacks[i].first);
      if (attacks[i].first == "register an own study" && login == rival) continue;  // a coordinator may: below
      CHECK_FALSE(attacks[i].second(*d, login));
      CHECK(studySnapshot(c.admin) == before);
    }
  }
  // The rival coordinator may register a study of her own (her own; nothing of Ada's changes).
  REQUIRE(saveStudy(bob, own));
  CHECK(studyOwner(c.admin, own.id) == rival);
  quiz::StudyProtocol spaced = own;  // "<study> …" would read, in the audit, as her study's rows
  spaced.id = own.id + " x";
  CHECK_FALSE(saveStudy(bob, spaced));
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM studies WHERE id = " + st + " AND owner = " + sqlText(c.coordinator)) == 1);

  // Even the owner cannot write what the program would not: an old session, an off-scale rating,
  // an invented item, trials that show a structure twice, a row never drawn, another owner's name.
  const std::string mid = studySnapshot(c.admin);
  auto resumed = enrolOrResume(coordinator, p, victim.participantId, victim.group);
  REQUIRE(resumed);
  CHECK(resumed->session == victim.session + 1);
  auto stale = recordRating(coordinator, victim, flip);
  REQUIRE_FALSE(stale);
  CHECK((stale.error().kind == ErrorKind::Conflict));
  const std::string trials = "'[" + std::string(R"({"position":0,"structure":"cochlea","a_condition":"wdt","b_condition":"bare","preset_a":"x","preset_b":"y"})") + "]'";
  for (const std::string& sql :
       {"SELECT at_record_rating(" + st + ", " + who + ", " + session + ", 0, 'shape', 1, 0, 0, 0, 0, '', NULL, NULL, NULL, NULL)",
        "SELECT at_record_rating(" + st + ", " + who + ", " + std::to_string(resumed->session) + ", 0, 'shape', 9, 0, 0, 0, 0, '', NULL, NULL, NULL, NULL)",
        "SELECT at_record_rating(" + st + ", " + who + ", " + std::to_string(resumed->session) + ", 0, 'beauty', 1, 0, 0, 0, 0, '', NULL, NULL, NULL, NULL)",
        "SELECT at_enrol_participant(" + st + ", 'P98', " + sqlText(p.groups[0]) + ", 0, " + trials + ")",
        "SELECT at_enrol_participant(" + st + ", 'P98', " + sqlText(p.groups[0]) + ", 1000, '[]')",
        "SELECT at_register_study(" + st + ", 'x', 'phantom', 1, '{}', " + sqlText(rival) + ")",
        "SELECT at_register_study('hers', '', 'phantom', 1, '{\"id\": \"hers\"}', " + sqlText(rival) + ")"}) {
    CAPTURE(sql);
    CHECK_FALSE(coordinator.exec(sql));
  }
  const std::string after = studySnapshot(c.admin);
  // Trials, ratings and the audit are unchanged (only the resume moved the participant's session).
  CHECK(after.substr(after.find("study_trials:")) == mid.substr(mid.find("study_trials:")));
}

TEST_CASE("StudyServer_ThroughTheCommandLine_TheCoordinatorsLoginRegistersAndRuns_AStudentsIsRefusedInOneLine") {
  if (!test::requireAppBinary("the study-on-the-server CLI test")) return;
  auto url = test::freshPostgresDatabase("the study-on-the-server CLI test");
  if (!url) return;
  test::SecureClass c(*url);
  test::TempDir dir;
  const quiz::StudyProtocol p = paperSurvey();
  const fs::path answers = dir.path() / "answers.jsonl";
  {
    std::ofstream out(answers);
    for (std::size_t s = 0; s < p.structures.size(); ++s) {
      nlohmann::json line = {{"trial", s + 1}, {"view_ms_a", 1000}, {"view_ms_b", 1200}, {"toggles", 1}};
      for (const auto& item : p.items) line["ratings"][item.id] = 1 + int(s % 5);
      out << line.dump() << "\n";
    }
  }
  const std::string file = (test::sourceDir() / "data/studies/paper_survey.json").string();
  const std::string run = "study run " + p.id + " --participant P01 --group " + p.groups[0] + " --answers '" + answers.string() + "'";
  Database admin = test::openAt(*url);
  const std::string empty = studySnapshot(admin);
  for (const std::string& args : {"study register '" + file + "'", run, "study register '" + file + "' --owner " + c.sam}) {
    CAPTURE(args);
    auto refused = test::runApp(args + " --db '" + c.samUrl + "'");
    CHECK(refused.exitCode != 0);
    CHECK(std::count(refused.err.begin(), refused.err.end(), '\n') == 1);
    CHECK(studySnapshot(admin) == empty);
  }

  auto registered = test::runApp("study register '" + file + "' --db '" + c.coordinatorUrl + "'");
  CAPTURE(registered.err);
  REQUIRE(registered.exitCode == 0);
  auto ran = test::runApp(run + " --db '" + c.coordinatorUrl + "'");
  CAPTURE(ran.err);
  REQUIRE(ran.exitCode == 0);
  auto status = test::runApp("study status " + p.id + " --db '" + c.coordinatorUrl + "'");
  REQUIRE(status.exitCode == 0);
  const std::string all = std::to_string(p.structures.size() * p.items.size());
  CHECK(status.out.find(all + "/" + all + " ratings  complete") != std::string::npos);
  CHECK(test::scalarCount(admin, "SELECT COUNT(*) FROM study_ratings") == std::int64_t(p.structures.size() * p.items.size()));
  CHECK(test::scalarCount(admin, "SELECT COUNT(*) FROM studies WHERE owner = " + sqlText(c.coordinator)) == 1);

  // After it, the student's attempts still change nothing, and she reads nothing of it.
  const std::string full = studySnapshot(admin);
  for (const std::string& args : {run, "study status " + p.id, "study export " + p.id + " --out '" + (dir.path() / "out").string() + "'",
                                  "study withdraw " + p.id + " P01 --reason spite"}) {
    CAPTURE(args);
    auto refused = test::runApp(args + " --db '" + c.samUrl + "'");
    CHECK(refused.exitCode != 0);
    CHECK(studySnapshot(admin) == full);
  }
  CHECK_FALSE(fs::exists(dir.path() / "out" / "responses_long.csv"));
  Database sam = test::openAt(c.samUrl);
  CHECK(test::scalarCount(sam, "SELECT COUNT(*) FROM study_trials") == 0);
}
