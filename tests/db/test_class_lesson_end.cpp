// A lesson's end on the class server is scored again whenever its answers are graded again: when
// the keys are published after the lesson ended, when a coordinator corrects an answer, and when
// the keys change. Its score is always the mean of the latest graded answer to each of the
// lesson's questions given up to that end (practice left out; blank while one waits for its key),
// worked out here from the stored answers, for random runs of a lesson (seed printed); each change
// of an end's score leaves an audit row naming who caused it.
#include <doctest/doctest.h>

#include <algorithm>
#include <ctime>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/class_accounts.h"
#include "db/class_lesson_keys.h"
#include "secure_class.h"
#include "test_databases.h"
#include "test_support.h"
#include "uuid.h"  // db/src

using namespace at;
using namespace at::db;
using nlohmann::json;

namespace {

using test::openAt;

const std::vector<std::string> kQuestions = {"toy.ossicles.name_stapes", "toy.ossicles.identify_incus",
                                             "toy.ossicles.locate_malleus"};

struct StoredAnswer {
  std::string uuid, question;
  std::int64_t at = 0;
  std::optional<double> score;
  bool practice = false;
};
struct StoredEnd {
  std::string uuid;
  std::int64_t at = 0;
  std::optional<double> score;
};

std::vector<StoredAnswer> answersOf(Database& admin, const std::string& user) {
  auto s = admin.prepare("SELECT uuid, question_id, occurred_at, score, practice FROM class_events"
                         " WHERE kind = 'answer' AND user_name = ?1 ORDER BY occurred_at");
  REQUIRE(s);
  s->bind(1, user);
  std::vector<StoredAnswer> out;
  while (*s->step()) out.push_back({s->text(0), s->text(1), s->int64(2), s->optionalReal(3), s->integer(4) == 1});
  return out;
}

std::vector<StoredEnd> endsOf(Database& admin, const std::string& user) {
  auto s = admin.prepare("SELECT uuid, occurred_at, score, payload FROM class_events"
                         " WHERE kind = 'lesson_finished' AND user_name = ?1 ORDER BY occurred_at");
  REQUIRE(s);
  s->bind(1, user);
  std::vector<StoredEnd> out;
  while (*s->step()) {
    out.push_back({s->text(0), s->int64(1), s->optionalReal(2)});
    const json payload = json::parse(s->text(3));  // the payload says the same score
    CHECK(payload.contains("score"));
    if (out.back().score) CHECK(payload["score"].get<double>() == doctest::Approx(*out.back().score));
    else CHECK(payload["score"].is_null());
  }
  return out;
}

// The end's score as the issue defines it, from the stored answers: per question, the latest graded
// answer given by then (a graded one before practice); none answered: 1; one waiting: blank; the
// mean of the graded ones (every one practice: blank).
std::optional<double> expectedScore(const std::vector<StoredAnswer>& answers, std::int64_t endAt) {
  int answered = 0;
  double sum = 0;
  int graded = 0;
  for (const std::string& q : kQuestions) {
    const StoredAnswer* latest = nullptr;
    for (const StoredAnswer& a : answers) {
      if (a.question != q || a.at > endAt) continue;
      if (!latest || (latest->practice && !a.practice) || (latest->practice == a.practice && a.at > latest->at)) latest = &a;
    }
    if (!latest) continue;
    ++answered;
    if (latest->practice) continue;
    if (!latest->score) return std::nullopt;
    sum += *latest->score;
    ++graded;
  }
  if (answered == 0) return 1.0;
  if (graded == 0) return std::nullopt;
  return sum / graded;
}

std::int64_t auditedEndChanges(Database& admin, const std::string& login) {
  return test::scalarCount(admin, "SELECT COUNT(*) FROM class_audit WHERE action = 'lesson_score' AND login = '" + login + "'");
}

// Every end's score equals expectedScore; returns how many differ from `before` (same order).
int checkEnds(Database& admin, const std::string& user, const std::vector<StoredEnd>& before) {
  const auto answers = answersOf(admin, user);
  const auto ends = endsOf(admin, user);
  REQUIRE(ends.size() == before.size());
  int changed = 0;
  for (std::size_t i = 0; i < ends.size(); ++i) {
    CAPTURE(i);
    const auto expected = expectedScore(answers, ends[i].at);
    CHECK(ends[i].score.has_value() == expected.has_value());
    if (ends[i].score && expected) CHECK(*ends[i].score == doctest::Approx(*expected));
    const bool differs = ends[i].score.has_value() != before[i].score.has_value() ||
                         (ends[i].score && std::abs(*ends[i].score - *before[i].score) > 1e-12);
    changed += differs ? 1 : 0;
  }
  return changed;
}

}  // namespace

TEST_CASE("ClassLessonEnd_AnEndSentBeforeTheKeysIsScoredWhenTheyArePublished_AgainOnACorrectionOrANewKey_EachChangeAudited") {
  auto url = test::freshPostgresDatabase("the lesson end test");
  if (!url) return;
  test::SecureClass c(*url, false);
  const std::uint64_t seed = test::freshSeed("ClassLessonEnd_AnEndSentBeforeTheKeysIsScored");
  INFO("seed " << seed);
  std::mt19937_64 random(seed);
  Database sam = openAt(c.samUrl);
  std::int64_t at = std::int64_t(std::time(nullptr)) - 100000;
  const auto send = [&](const std::string& kind, const std::string& question, const json& answer) {
    auto s = sam.prepare("SELECT at_record_event(?1, ?2, ?3, ?4, ?5, 'toy.ossicles', ?6, '', ?7, ?8, ?9)");
    REQUIRE(s);
    const json payload = kind == "answer" ? json{{"source", "lesson"}, {"answer", answer}, {"correct", true}, {"score", 1.0}}
                                          : json::object();
    s->bind(1, newUuid()).bind(2, c.code).bind(3, c.sam).bind(4, kind).bind(5, at++).bind(6, question);
    s->bind(7, kind == "answer" ? std::optional<std::int64_t>(1) : std::nullopt);
    s->bind(8, kind == "answer" ? std::optional<double>(1.0) : std::nullopt).bind(9, payload.dump());
    auto row = s->step();
    REQUIRE_MESSAGE(row, (row ? "" : row.error().message));
    CHECK(s->text(0) == "stored");
  };
  const auto randomAnswer = [&](const std::string& question) -> json {
    if (question == kQuestions[0]) {
      const char* texts[] = {"stapes", "Stirrup", "incus", "stapez", "Malleus"};
      return {{"text", texts[random() % 5]}};
    }
    if (question == kQuestions[1]) return {{"choice", int(random() % 3)}};
    const char* picks[] = {"malleus", "incus", "stapes"};
    return {{"pick", picks[random() % 3]}, {"distance_mm", double(random() % 3)}};
  };
  // A run of the lesson: every question answered once or more the first time (an end needs them
  // all), any of them the later times; the end sent before any key exists.
  const auto playRun = [&](bool first) {
    send("lesson_started", "", nullptr);
    std::vector<std::string> asked;
    for (const std::string& q : kQuestions) {
      const int times = first ? 1 + int(random() % 3) : int(random() % 3);
      for (int i = 0; i < times; ++i) asked.push_back(q);
    }
    std::shuffle(asked.begin(), asked.end(), random);
    for (const std::string& q : asked) send("answer", q, randomAnswer(q));
    send("lesson_finished", "", nullptr);
  };
  const int runs = 2 + int(random() % 3);
  for (int r = 0; r < runs; ++r) playRun(r == 0);

  // No key yet: every end waits (blank), as its answers do.
  std::vector<StoredEnd> before = endsOf(c.admin, c.sam);
  REQUIRE(int(before.size()) == runs);
  for (const StoredEnd& e : before) CHECK_FALSE(e.score);
  CHECK(checkEnds(c.admin, c.sam, before) == 0);

  // The keys published after the lesson ended: every end scored now, each change audited as the
  // instructor's (the locate picks, made without a pixel on the question's picture, are practice).
  Database instructor = openAt(c.instructorUrl);
  REQUIRE(publishLessonKeys(instructor, c.code, test::toyLessonKeys(), std::nullopt));
  int changed = checkEnds(c.admin, c.sam, before);
  CHECK(changed == runs);  // every end has a graded name and identify answer by then
  CHECK(auditedEndChanges(c.admin, c.instructor) == changed);

  // A coordinator's correction of the latest graded answer before the first end (so that end
  // changes), and of a practice pick when there is one: the ends follow, audited as hers.
  before = endsOf(c.admin, c.sam);
  auto answers = answersOf(c.admin, c.sam);
  const StoredAnswer* latest = nullptr;
  for (const StoredAnswer& a : answers)
    if (!a.practice && a.at < before.front().at) latest = &a;
  REQUIRE(latest);
  REQUIRE(latest->score);
  const double corrected = *latest->score >= 1 ? 0.0 : 1.0;
  Database coordinator = openAt(c.coordinatorUrl);
  REQUIRE(correctClassEvent(coordinator, latest->uuid, corrected >= 1, corrected, "marked by hand", std::nullopt));
  int correctedChanges = checkEnds(c.admin, c.sam, before);
  CHECK(correctedChanges >= 1);
  CHECK(auditedEndChanges(c.admin, c.coordinator) == correctedChanges);
  std::vector<std::string> practiceUuids;
  for (const StoredAnswer& a : answers)
    if (a.practice) practiceUuids.push_back(a.uuid);
  if (!practiceUuids.empty()) {
    before = endsOf(c.admin, c.sam);
    REQUIRE(correctClassEvent(coordinator, practiceUuids[random() % practiceUuids.size()], false, 0.5,
                              "the pick was on the malleus's neck", std::nullopt));
    const int more = checkEnds(c.admin, c.sam, before);
    CHECK(auditedEndChanges(c.admin, c.coordinator) == correctedChanges + more);
    correctedChanges += more;
  }

  // A changed key: the answers nobody corrected are graded again, and the ends with them.
  before = endsOf(c.admin, c.sam);
  std::vector<std::string> changedKeys = test::toyLessonKeys();
  for (std::string& k : changedKeys) {
    json key = json::parse(k);
    if (key["question_id"] == kQuestions[1]) key["key_choice"] = (key["key_choice"].get<int>() + 1) % 3;
    k = key.dump();
  }
  const std::int64_t instructorChanges = auditedEndChanges(c.admin, c.instructor);
  REQUIRE(publishLessonKeys(instructor, c.code, changedKeys, std::nullopt));
  changed = checkEnds(c.admin, c.sam, before);
  CHECK(auditedEndChanges(c.admin, c.instructor) - instructorChanges == changed);

  // A run after the keys: its end is scored as it arrives, by the same rule.
  playRun(false);
  before = endsOf(c.admin, c.sam);
  CHECK(checkEnds(c.admin, c.sam, before) == 0);
  CHECK(before.back().score.has_value());
  // Every audited change names the student's end it changed and its old and new score.
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_audit WHERE action = 'lesson_score' AND (target NOT LIKE '" +
                                       c.sam + " %' OR new_value NOT LIKE '{\"score\" : %' OR old_value IS NULL)") == 0);
  MESSAGE("seed " << seed << ": " << runs + 1 << " runs; " << correctedChanges << " ends changed by the corrections, "
                  << changed << " by the new key");
}

TEST_CASE("ClassLessonEnd_AServerUpgradedToRescoringScoresTheEndsItAlreadyHeld_Audited") {
  auto url = test::freshPostgresDatabase("the lesson end test");
  if (!url) return;
  std::string endUuid, code, sam;
  {
    test::SecureClass c(*url, false);
    code = c.code;
    sam = c.sam;
    Database samDb = openAt(c.samUrl);
    std::int64_t at = std::int64_t(std::time(nullptr)) - 1000;
    for (const auto& [kind, question, answer] :
         std::vector<std::tuple<std::string, std::string, json>>{{"lesson_started", "", nullptr},
                                                                 {"answer", kQuestions[0], {{"text", "stapes"}}},
                                                                 {"answer", kQuestions[1], {{"choice", 0}}},
                                                                 {"answer", kQuestions[2], {{"pick", "malleus"}, {"distance_mm", 0}}},
                                                                 {"lesson_finished", "", nullptr}}) {
      auto s = samDb.prepare("SELECT at_record_event(?1, ?2, ?3, ?4, ?5, 'toy.ossicles', ?6, '', ?7, ?8, ?9)");
      REQUIRE(s);
      const json payload = kind == "answer" ? json{{"answer", answer}} : json::object();
      s->bind(1, newUuid()).bind(2, c.code).bind(3, c.sam).bind(4, kind).bind(5, at++).bind(6, question);
      s->bind(7, kind == "answer" ? std::optional<std::int64_t>(1) : std::nullopt);
      s->bind(8, kind == "answer" ? std::optional<double>(1.0) : std::nullopt).bind(9, payload.dump());
      REQUIRE(*s->step());
      CHECK(s->text(0) == "stored");
    }
    // A server before re-scoring: the keys published after the lesson ended left its end blank.
    REQUIRE(c.admin.exec("DROP TRIGGER class_events_rescore_lesson_ends ON class_events"));
    REQUIRE(c.admin.exec("DROP FUNCTION at_rescore_lesson_ends()"));
    Database instructor = openAt(c.instructorUrl);
    REQUIRE(publishLessonKeys(instructor, c.code, test::toyLessonKeys(), std::nullopt));
    auto ends = endsOf(c.admin, c.sam);
    REQUIRE(ends.size() == 1);
    CHECK_FALSE(ends[0].score);
    endUuid = ends[0].uuid;
    REQUIRE(c.admin.exec("DROP FUNCTION at_lesson_end_score(text, text, text, bigint)"));
    test::forceSchemaVersion(c.admin, 25);
  }
  Database upgraded = openAt(*url);  // migration 26 runs again
  const auto answers = answersOf(upgraded, sam);
  const auto ends = endsOf(upgraded, sam);
  REQUIRE(ends.size() == 1);
  const auto expected = expectedScore(answers, ends[0].at);
  REQUIRE(expected);
  REQUIRE(ends[0].score);
  CHECK(*ends[0].score == doctest::Approx(*expected));
  CHECK(test::scalarCount(upgraded, "SELECT COUNT(*) FROM class_audit WHERE action = 'lesson_score' AND target = '" + sam +
                                        " " + endUuid + "' AND old_value = '{\"score\" : null}'") == 1);
}
