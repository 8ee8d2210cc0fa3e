// One class view: instructor analytics on a class server counts what `class progress` counts —
// the students who learnt on their own machines and reached the server through the outbox
// included — read through PgBouncer, as the lab machines reach the server. Both count graded
// answers only: those still waiting for their keys are counted apart, in both.
#include <doctest/doctest.h>

#include <algorithm>
#include <ctime>
#include <map>
#include <random>
#include <set>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/analytics_store.h"
#include "db/class_server.h"
#include "db/course_store.h"
#include "db/sql_repositories.h"
#include "lessons/analytics.h"
#include "lessons/lesson_engine.h"
#include "pooled_postgres.h"
#include "secure_class.h"  // toyLessonKeys
#include "test_databases.h"
#include "test_support.h"
#include "toy_course.h"
#include "toy_play.h"

using namespace at;
using namespace at::db;
using namespace at::lessons;

namespace {

using test::openAt;

// A student's laptop: its own SQLite file with the toy course, joined to the class.
struct Laptop {
  Database db;
  std::int64_t userId = 0;
  SqlCurriculumRepository curriculum;
  SqlProgressRepository progress;
  test::ToyKeys keys;

  Laptop(const std::string& path, const std::string& name) : db(openAt(path)), curriculum(db, test::toyBuiltin()), progress(db) {
    REQUIRE(storeCourse(db, test::toyCourse(), "toy"));
    SqlUserRepository users(db);
    auto user = users.createUser(name, Role::Student, "");
    REQUIRE(user);
    userId = user->id;
  }

  // Plays `lessonId`, answering right where `right(n)` says, stopping after `stopAfter` answers.
  void play(const std::string& lessonId, const std::function<bool(int)>& right, int stopAfter) {
    LessonEngine engine(curriculum, progress, keys);
    auto started = engine.start(userId, lessonId);
    REQUIRE_MESSAGE(started, (started ? "" : started.error().message));
    test::playAnswering(engine, right, stopAfter);
    if (engine.atEnd()) REQUIRE(engine.finish());
  }
};

}  // namespace

TEST_CASE("ClassView_AnalyticsOnTheServerCountsWhatClassProgressCounts_OutboxStudentsIncluded") {
  if (test::testingOnPostgres()) return;  // runs its own server: once is enough
  test::PooledPostgres pooler(20, 5);
  auto urls = test::pooledDatabase(pooler, "the class view test");
  if (!urls) return;
  const std::uint64_t seed = test::freshSeed("ClassView_AnalyticsOnTheServer");
  INFO("seed " << seed);
  std::mt19937 random{unsigned(seed)};
  test::TempDir dir;
  Database server = openAt(urls->pooled);
  REQUIRE(storeCourse(server, test::toyCourse(), "toy"));
  auto made = createClass(server, "Ear anatomy", "dr_ada");
  REQUIRE(made);
  auto other = createClass(server, "Another class", "dr_ada");
  REQUIRE(other);
  // Part of the course's keys, published before the students play or after their answers arrived:
  // the name question's always (graded answers), the identify question of the first lesson never
  // (answers waiting), the rest at random.
  std::vector<std::string> keys;
  for (const std::string& k : test::toyLessonKeys()) {
    const std::string question = nlohmann::json::parse(k)["question_id"];
    if (question == "toy.ossicles.name_stapes" || (question != "toy.ossicles.identify_incus" && random() % 2)) keys.push_back(k);
  }
  const bool keysFirst = random() % 2 == 0;
  const auto publish = [&] {
    auto published = publishLessonKeys(server, made->code, keys, std::string("dr_ada"));
    REQUIRE_MESSAGE(published, (published ? "" : published.error().message));
  };
  if (keysFirst) publish();

  // Five laptop students of the class (one never plays) and one of another class; each plays the
  // first lesson and, at random, part of the second, with a random pattern of right answers.
  const std::vector<std::string> names = {"ann", "ben", "cat", "dan", "eve"};
  std::vector<std::unique_ptr<Laptop>> laptops;
  for (std::size_t i = 0; i <= names.size(); ++i) {
    const bool elsewhere = i == names.size();
    const std::string name = elsewhere ? "zed" : names[i];
    const std::string code = elsewhere ? other->code : made->code;
    laptops.push_back(std::make_unique<Laptop>((dir.path() / (name + ".db")).string(), name));
    REQUIRE(joinClass(server, code, name));
    REQUIRE(rememberMembership(laptops.back()->db, {name, code, urls->pooled, ClassRole::Student}));
    if (name == "dan") continue;
    // Right and wrong alternating from a right first answer, or all right (the patterns toy_play.h
    // is written for: a toy question answered wrong first may not be graded wrong).
    const bool allRight = random() % 2 == 0;
    const auto right = [allRight](int n) { return allRight || n % 2 == 0; };
    laptops.back()->play("toy.ossicles", right, 1 << 30);
    if (random() % 2) laptops.back()->play("toy.middle", right, int(random() % 4));
    auto sent = syncOutbox(laptops.back()->db);
    REQUIRE(sent);
    CHECK(sent->complete());
  }
  if (!keysFirst) publish();
  // A lab machine's user on the server itself, in no class: analytics' class, not class progress'.
  SqlUserRepository serverUsers(server);
  REQUIRE(serverUsers.createUser("lab_user", Role::Student, ""));

  auto progress = classProgress(server, made->code, "dr_ada");
  REQUIRE_MESSAGE(progress, (progress ? "" : progress.error().message));
  SqlCurriculumRepository curriculum(server, test::toyBuiltin());
  auto input = loadAnalyticsInput(server, curriculum, test::toyCourse().id, made->code);
  REQUIRE_MESSAGE(input, (input ? "" : input.error().message));
  const ClassAnalytics analytics = computeAnalytics(*input, std::int64_t(std::time(nullptr)));

  // The same students, answers, right answers, structures and lessons, student by student.
  REQUIRE(progress->students.size() == names.size());
  CHECK(analytics.classSize == int(names.size()));
  std::map<std::int64_t, std::string> nameOf;
  for (const User& u : input->students) nameOf[u.id] = u.name;
  struct Counts {
    int answers = 0, correct = 0;
    std::set<std::string> structures, started, finished;
  };
  std::map<std::string, Counts> fromAnalytics;
  for (const ClassAnswer& a : input->answers) {
    Counts& c = fromAnalytics[nameOf.at(a.userId)];
    ++c.answers;
    c.correct += a.correct ? 1 : 0;
    c.structures.insert(a.structureId);
  }
  for (const Attempt& a : input->attempts) {
    fromAnalytics[nameOf.at(a.userId)].started.insert(a.lessonId);
    if (a.finishedAt) fromAnalytics[nameOf.at(a.userId)].finished.insert(a.lessonId);
  }
  int total = 0, waiting = 0;
  for (const StudentClassProgress& p : progress->students) {
    CAPTURE(p.userName);
    const Counts& c = fromAnalytics[p.userName];
    CHECK(c.answers == p.answers);
    CHECK(c.correct == p.correct);
    CHECK(int(c.structures.size()) == p.structures);
    CHECK(int(c.started.size()) == p.lessonsStarted);
    CHECK(int(c.finished.size()) == p.lessonsFinished);
    total += p.answers;
    waiting += p.ungraded;
  }
  CHECK(total > 0);
  CHECK(waiting > 0);
  CHECK(input->waitingAnswers == waiting);
  CHECK(analytics.answers == total);
  // Per lesson: the finishers, and the mean of each one's best end score among the ends the server
  // has scored; an end waiting for its keys (blank score) counts as finished, not as a score of 0.
  auto ends = server.prepare("SELECT user_name, lesson_id, score FROM class_events"
                             " WHERE kind = 'lesson_finished' AND practice = 0 AND class_code = ?1");
  REQUIRE(ends);
  ends->bind(1, made->code);
  std::map<std::string, std::set<std::string>> finishers;              // lesson → students
  std::map<std::string, std::map<std::string, double>> bestKnownScore;  // lesson → student → best
  while (*ends->step()) {
    finishers[ends->text(1)].insert(ends->text(0));
    if (const auto score = ends->optionalReal(2)) {
      double& best = bestKnownScore[ends->text(1)].try_emplace(ends->text(0), 0.0).first->second;
      best = std::max(best, *score);
    }
  }
  int unknownScores = 0;
  for (const LessonCompletion& l : analytics.lessons) {
    CAPTURE(l.lessonId);
    CHECK(l.finished == int(finishers[l.lessonId].size()));
    const auto& known = bestKnownScore[l.lessonId];
    CHECK(l.scoresUnknown == int(finishers[l.lessonId].size() - known.size()));
    unknownScores += l.scoresUnknown;
    REQUIRE(l.meanBestScore.has_value() == !known.empty());
    double sum = 0;
    for (const auto& [student, best] : known) sum += best;
    if (!known.empty()) CHECK(*l.meanBestScore == doctest::Approx(sum / double(known.size())));
  }
  CHECK(unknownScores > 0);  // the first lesson's identify question never gets its key

  // Per structure too.
  std::map<std::string, std::pair<int, int>> byStructure;
  for (const StructureStats& s : analytics.structures) byStructure[s.structureId] = {s.answers, s.correct};
  for (const StructureClassProgress& s : progress->structures) {
    CAPTURE(s.structureId);
    CHECK(byStructure[s.structureId] == std::make_pair(s.answers, s.correct));
  }

  // Without a class named: every class's outbox students and the server's own users.
  auto everyone = loadAnalyticsInput(server, curriculum, test::toyCourse().id, std::nullopt);
  REQUIRE(everyone);
  std::set<std::string> all;
  for (const User& u : everyone->students) all.insert(u.name);
  CHECK(all == std::set<std::string>{"ann", "ben", "cat", "dan", "eve", "lab_user", "zed"});
}
