// The lessons/ storage interfaces over SQLite: round trips, idempotent seeding, one-transaction
// answers, resuming through the LessonEngine, and concurrent recorders.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <thread>

#include "db/course_store.h"
#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/exam_store.h"
#include "db/sql_repositories.h"
#include "lessons/course_json.h"
#include "lessons/lesson_engine.h"
#include "lessons/scheduling.h"
#include "quiz/answer_json.h"
#include "test_databases.h"
#include "test_support.h"
#include "toy_course.h"
#include "toy_play.h"

namespace fs = std::filesystem;
using namespace at;
using namespace at::db;
using namespace at::lessons;

namespace {

std::int64_t countRows(Database& db, const std::string& table) {
  auto s = db.prepare("SELECT count(*) FROM " + table);
  REQUIRE(s);
  REQUIRE(*s->step());
  return s->int64(0);
}

// The learner update one answer with `rating` at `at` gives a structure never answered before.
LearnerUpdate firstAnswer(std::int64_t userId, const std::string& structure, Rating rating, UnixSeconds at,
                          double abilityAfter = 1500, double difficultyAfter = 1500) {
  LearnerUpdate u;
  const StructureProgress before{.userId = userId, .structureId = structure, .memory = {}};
  u.progress = scheduleAnswer(before, rating, rating != Rating::Again, at, Fsrs());
  u.rating = rating;
  u.abilityAfter = abilityAfter;
  u.difficultyAfter = difficultyAfter;
  return u;
}

Database openAt(const std::string& location) {
  auto db = Database::open(location);
  REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
  return std::move(*db);
}

Database openFresh(const test::TempDir& dir, const std::string& name = "r.db") {
  return openAt(test::freshDatabase(dir, name));
}

}  // namespace

TEST_CASE("A stored course reads back identical, including texts with quotes and SQL") {
  test::TempDir dir;
  Database db = openFresh(dir);
  Course course = test::toyCourse();
  course.lessons[0].steps[0].show.text = "It's the \"stirrup\"; DROP TABLE lessons; -- really";
  course.synonyms["incus"] = {"anvil", "l'enclume"};
  // A free camera and a clipping plane on a show step and on a question's scene (schema 11).
  course.lessons[0].steps[0].show.camera = StepCamera{{1.5, -2, 3}, {0, 0.6, -0.8}, {0, 0.8, 0.6}, 42.25};
  course.lessons[0].steps[0].show.clip = StepClip{{0, 0, -1}, -3.5};
  for (Step& step : course.lessons[0].steps)
    if (step.scene) step.scene->clip = StepClip{{1, 0, 0}, 0.75};
  auto stored = storeCourse(db, course, "memory");
  REQUIRE_MESSAGE(stored, (stored ? "" : stored.error().message));
  CHECK(bool(*stored == SeedOutcome::Added));

  SqlCurriculumRepository repo(db, test::toyBuiltin());
  auto back = repo.course("toy");
  REQUIRE_MESSAGE(back, (back ? "" : back.error().message));
  CHECK(courseToJson(*back) == courseToJson(course));
  CHECK(back->lessons[0].steps[0].show.camera == course.lessons[0].steps[0].show.camera);
  CHECK(back->lessons[0].steps[0].show.clip == course.lessons[0].steps[0].show.clip);
  for (std::size_t i = 0; i < course.lessons[0].steps.size(); ++i)
    if (course.lessons[0].steps[i].scene) {
      REQUIRE(back->lessons[0].steps[i].scene.has_value());
      CHECK(back->lessons[0].steps[i].scene->clip == StepClip{{1, 0, 0}, 0.75});
    }
  auto lesson = repo.lesson("toy.middle");
  REQUIRE(lesson);
  CHECK(lesson->prerequisites == std::vector<std::string>{"toy.ossicles"});
  auto q = repo.question("toy.middle.order_drill");
  REQUIRE(q);
  CHECK(q->order.entryStructure == "malleus");
  auto all = repo.courses();
  REQUIRE(all);
  CHECK(all->size() == 1);

  CHECK(repo.lesson("nope").error().message == "unknown lesson 'nope'");
  CHECK(repo.course("nope").error().message == "unknown course 'nope'");
  CHECK(repo.question("nope").error().message == "unknown question 'nope'");
  auto structures = repo.structures("toy");
  REQUIRE(structures);
  CHECK(structures->size() == 5);
  CHECK(!repo.structures("nowhere"));
}

TEST_CASE("Seeding the same course files twice changes nothing; a newer version replaces the content") {
  test::TempDir dir;
  Database db = openFresh(dir);
  fs::create_directories(dir / "courses");
  Course course = test::toyCourse(1);
  { std::ofstream(dir / "courses" / "toy.json") << courseToJson(course); }

  auto first = seedCourses(db, dir / "courses");
  REQUIRE_MESSAGE(first, (first ? "" : first.error().message));
  REQUIRE(first->size() == 1);
  CHECK(bool((*first)[0].outcome == SeedOutcome::Added));
  const auto counts = [&] {
    return std::vector<std::int64_t>{countRows(db, "courses"), countRows(db, "lessons"), countRows(db, "steps"),
                                     countRows(db, "questions"), countRows(db, "lesson_prerequisites")};
  };
  const auto afterFirst = counts();
  CHECK(afterFirst == std::vector<std::int64_t>{1, 2, 8, 6, 1});

  for (int i = 0; i < 3; ++i) {
    auto again = seedCourses(db, dir / "courses");
    REQUIRE(again);
    CHECK(bool((*again)[0].outcome == SeedOutcome::Unchanged));
    CHECK(counts() == afterFirst);
  }

  // A learner answers before the course is updated: the answer must survive the update.
  SqlUserRepository users(db);
  SqlProgressRepository progress(db);
  auto user = users.createUser("ana", Role::Student, "");
  REQUIRE(user);
  auto attempt = progress.startAttempt(user->id, "toy.ossicles", LessonMode::Guided, 100);
  REQUIRE(attempt);
  AnswerRecord record;
  record.response.attemptId = attempt->id;
  record.response.stepIndex = 1;
  record.response.questionId = "toy.ossicles.name_stapes";
  record.response.structureId = "stapes";
  record.response.answer.text = "stapes";
  record.update = firstAnswer(user->id, "stapes", Rating::Good, 100);
  REQUIRE(progress.recordAnswer(record));

  Course v2 = test::toyCourse(2);
  v2.lessons[1].steps.pop_back();  // one question fewer
  v2.lessons[0].title = "The ossicles";
  { std::ofstream(dir / "courses" / "toy.json") << courseToJson(v2); }
  auto updated = seedCourses(db, dir / "courses");
  REQUIRE(updated);
  CHECK(bool((*updated)[0].outcome == SeedOutcome::Updated));
  CHECK(counts() == std::vector<std::int64_t>{1, 2, 7, 5, 1});
  SqlCurriculumRepository repo(db, test::toyBuiltin());
  CHECK(courseToJson(*repo.course("toy")) == courseToJson(v2));
  CHECK(countRows(db, "responses") == 1);
  CHECK(countRows(db, "attempts") == 1);

  // An older file never downgrades what is stored.
  { std::ofstream(dir / "courses" / "toy.json") << courseToJson(test::toyCourse(1)); }
  auto older = seedCourses(db, dir / "courses");
  REQUIRE(older);
  CHECK(bool((*older)[0].outcome == SeedOutcome::KeptNewer));
  CHECK(repo.lesson("toy.ossicles")->title == "The ossicles");
}

TEST_CASE("A course reusing another course's lesson id is refused and writes nothing") {
  test::TempDir dir;
  Database db = openFresh(dir);
  REQUIRE(storeCourse(db, test::toyCourse(), "a"));
  Course other = test::toyCourse();
  other.id = "other";
  other.lessons.resize(1);  // its lesson id "toy.ossicles" belongs to course "toy"
  auto refused = storeCourse(db, other, "b");
  REQUIRE(!refused);
  CHECK(refused.error().message.find("'toy.ossicles'") != std::string::npos);
  CHECK((refused.error().kind == ErrorKind::Conflict));
  CHECK(countRows(db, "courses") == 1);
  CHECK(countRows(db, "lessons") == 2);
}

TEST_CASE("Seeding reports a broken course file by name") {
  test::TempDir dir;
  Database db = openFresh(dir);
  fs::create_directories(dir / "courses");
  { std::ofstream(dir / "courses" / "broken.json") << "{\"schema\": 1, \"id\": \"x\""; }
  auto seeded = seedCourses(db, dir / "courses");
  REQUIRE(!seeded);
  CHECK(seeded.error().message.find("broken.json") != std::string::npos);
  CHECK(countRows(db, "courses") == 0);
}

TEST_CASE("Users are created once, found by pseudonym, and hostile names are kept verbatim") {
  test::TempDir dir;
  Database db = openFresh(dir);
  SqlUserRepository users(db);
  const std::string hostile = "x'); DELETE FROM users; --\"";
  auto u = users.createUser(hostile, Role::Coordinator, "group; DROP TABLE users");
  REQUIRE(u);
  CHECK(u->id > 0);
  auto found = users.findUser(hostile);
  REQUIRE(found);
  REQUIRE(found->has_value());
  CHECK(bool((*found)->role == Role::Coordinator));
  CHECK((*found)->group == "group; DROP TABLE users");
  CHECK(users.user(u->id)->name == hostile);
  auto taken = users.createUser(hostile, Role::Student, "");
  REQUIRE(!taken);
  CHECK(taken.error().message.find("already taken") != std::string::npos);
  CHECK((taken.error().kind == ErrorKind::Conflict));
  CHECK(!users.createUser("", Role::Student, ""));
  CHECK(!users.findUser("nobody")->has_value());
  CHECK(!users.user(999));
  CHECK(users.users()->size() == 1);
}

TEST_CASE("An answer is stored with its progress, ability and difficulty in one transaction") {
  test::TempDir dir;
  Database db = openFresh(dir);
  SqlUserRepository users(db);
  SqlProgressRepository progress(db);
  auto user = users.createUser("ben", Role::Student, "");
  REQUIRE(user);
  CHECK(!progress.openAttempt(user->id, "toy.ossicles")->has_value());
  auto attempt = progress.startAttempt(user->id, "toy.ossicles", LessonMode::QuizOnly, 1000);
  REQUIRE(attempt);
  auto open = progress.openAttempt(user->id, "toy.ossicles");
  REQUIRE(open->has_value());
  CHECK(bool((*open)->mode == LessonMode::QuizOnly));
  CHECK((*open)->startedAt == 1000);

  AnswerRecord r;
  r.response.attemptId = attempt->id;
  r.response.stepIndex = 3;
  r.response.questionId = "toy.ossicles.locate_malleus";
  r.response.structureId = "malleus";
  r.response.answer.pick = quiz::Pick{.structure = "incus", .distanceMm = 0.25, .pixel = std::nullopt, .view = ""};
  r.response.correct = true;
  r.response.score = 1;
  r.response.latencyMs = 4321;
  r.response.render = {"malleus_wdt", "wdt", 0.3, 1.7, 0.9};
  r.response.answeredAt = 1010;
  r.update = firstAnswer(user->id, "malleus", Rating::Easy, 1010, 1516, 1484);
  auto id = progress.recordAnswer(r);
  REQUIRE_MESSAGE(id, (id ? "" : id.error().message));

  auto responses = progress.responses(attempt->id);
  REQUIRE(responses);
  REQUIRE(responses->size() == 1);
  const Response& back = (*responses)[0];
  CHECK(back.id == *id);
  CHECK(back.stepIndex == 3);
  CHECK(back.structureId == "malleus");
  CHECK(quiz::answerToJson(back.answer) == quiz::answerToJson(r.response.answer));
  CHECK(back.latencyMs == 4321);
  CHECK(back.render.presetId == "malleus_wdt");
  CHECK(back.render.t == doctest::Approx(0.3));
  CHECK(back.render.alpha == doctest::Approx(1.7));
  CHECK(back.render.beta == doctest::Approx(0.9));
  CHECK(back.answeredAt == 1010);
  auto p = progress.progress(user->id, "malleus");
  REQUIRE(p->has_value());
  CHECK(((*p)->memory.phase == MemoryPhase::Review));
  CHECK((*p)->memory.stability == doctest::Approx(r.update.progress.memory.stability));
  CHECK((*p)->memory.due == r.update.progress.memory.due);
  CHECK((*p)->memory.lastReview == 1010);
  CHECK((*p)->memory.reviews == 1);
  CHECK(*progress.ability(user->id) == std::optional<double>(1516));
  CHECK(*progress.questionDifficulty("toy.ossicles.locate_malleus") == std::optional<double>(1484));
  CHECK(!progress.questionDifficulty("never")->has_value());

  // The review log holds the answer with its rating and the state it produced.
  auto log = progress.reviewLog(user->id);
  REQUIRE(log);
  REQUIRE(log->size() == 1);
  const ReviewLogEntry& e = (*log)[0];
  CHECK((e.source == AnswerSource::Lesson));
  CHECK((e.rating == Rating::Easy));
  CHECK(e.questionId == "toy.ossicles.locate_malleus");
  CHECK(e.latencyMs == 4321);
  CHECK(e.reviewedAt == 1010);
  CHECK((e.phaseBefore == MemoryPhase::New));
  CHECK(e.elapsedDays == -1);
  CHECK((e.after.phase == MemoryPhase::Review));
  CHECK(e.after.due == r.update.progress.memory.due);
  CHECK_FALSE(e.rebuilt);

  // The same step again is refused, and nothing of it is written (the memory state stays).
  AnswerRecord again = r;
  again.update = firstAnswer(user->id, "malleus", Rating::Again, 1010, 1400);
  auto dup = progress.recordAnswer(again);
  REQUIRE(!dup);
  CHECK(dup.error().message.find("already answered") != std::string::npos);
  CHECK((dup.error().kind == ErrorKind::Conflict));
  AnswerRecord orphan = r;
  orphan.response.attemptId = 987654;
  auto noAttempt = progress.recordAnswer(orphan);
  REQUIRE(!noAttempt);
  CHECK((noAttempt.error().kind == ErrorKind::NotFound));
  CHECK(noAttempt.error().message.find("unknown attempt 987654") != std::string::npos);
  CHECK(((*progress.progress(user->id, "malleus"))->memory.phase == MemoryPhase::Review));
  CHECK(countRows(db, "review_log") == 1);
  CHECK(*progress.ability(user->id) == std::optional<double>(1516));
  CHECK(countRows(db, "responses") == 1);

  REQUIRE(!*progress.hasFinished(user->id, "toy.ossicles"));
  REQUIRE(progress.finishAttempt(attempt->id, 1100, 0.75));
  CHECK(*progress.hasFinished(user->id, "toy.ossicles"));
  CHECK(!progress.openAttempt(user->id, "toy.ossicles")->has_value());
  CHECK(!progress.finishAttempt(9999, 1, 0));
  auto attempts = progress.attempts(user->id);
  REQUIRE(attempts);
  REQUIRE(attempts->size() == 1);
  CHECK((*attempts)[0].score == doctest::Approx(0.75));
  CHECK(progress.allProgress(user->id)->size() == 1);
}

TEST_CASE("The LessonEngine on the store resumes a lesson at the next step after the process is gone") {
  test::TempDir dir;
  const std::string path = test::freshDatabase(dir, "e.db");
  std::int64_t userId = 0;
  {
    Database db = openAt(path);
    REQUIRE(storeCourse(db, test::toyCourse(), "toy"));
    SqlUserRepository users(db);
    userId = users.createUser("cleo", Role::Student, "")->id;
  }
  {
    auto db = Database::open(path);
    REQUIRE(db);
    SqlCurriculumRepository curriculum(*db, test::toyBuiltin());
    SqlProgressRepository progress(*db);
    test::ToyKeys keys;
    LessonEngine engine(curriculum, progress, keys);
    // Prerequisite not finished yet.
    auto locked = engine.start(userId, "toy.middle");
    REQUIRE(!locked);
    CHECK(locked.error().message.find("toy.ossicles") != std::string::npos);
    LessonEngine first(curriculum, progress, keys);
    REQUIRE(first.start(userId, "toy.ossicles"));
    CHECK(test::playRight(first, 2) == 2);  // then the "process" goes away
  }
  auto db = Database::open(path);
  REQUIRE(db);
  SqlCurriculumRepository curriculum(*db, test::toyBuiltin());
  SqlProgressRepository progress(*db);
  test::ToyKeys keys;
  LessonEngine engine(curriculum, progress, keys);
  REQUIRE(engine.start(userId, "toy.ossicles"));
  CHECK(engine.resumed());
  auto view = engine.current();
  REQUIRE(view);
  CHECK(view->questionId == "toy.ossicles.locate_malleus");
  CHECK(test::playRight(engine) == 1);
  auto score = engine.finish();
  REQUIRE(score);
  CHECK(*score == doctest::Approx(1.0));
  CHECK(countRows(*db, "responses") == 3);

  LessonEngine next(curriculum, progress, keys);
  REQUIRE(next.start(userId, "toy.middle"));
  CHECK(test::playRight(next) == 3);
  REQUIRE(next.finish());
  CHECK(countRows(*db, "responses") == 6);
  auto ability = progress.ability(userId);
  REQUIRE(ability->has_value());
  CHECK(**ability > 1500);
}

TEST_CASE("Two connections recording answers for the same user at once lose nothing") {
  test::TempDir dir;
  const std::string path = test::freshDatabase(dir, "c.db");
  std::int64_t userId = 0, attemptA = 0, attemptB = 0;
  {
    Database db = openAt(path);
    SqlUserRepository users(db);
    SqlProgressRepository progress(db);
    userId = users.createUser("dana", Role::Student, "")->id;
    attemptA = progress.startAttempt(userId, "a", LessonMode::Guided, 1)->id;
    attemptB = progress.startAttempt(userId, "b", LessonMode::Guided, 1)->id;
  }
  constexpr int kAnswers = 120;
  auto recorder = [&](std::int64_t attempt, std::string* error) {
    auto db = Database::open(path);
    if (!db) {
      *error = db.error().message;
      return;
    }
    SqlProgressRepository progress(*db);
    for (int i = 0; i < kAnswers; ++i) {
      AnswerRecord r;
      r.response.attemptId = attempt;
      r.response.stepIndex = i;
      r.response.questionId = std::string("q").append(std::to_string(i % 7));
      r.response.structureId = std::string("s").append(std::to_string(i % 5));
      r.response.answer.choice = i % 3;
      r.update = firstAnswer(userId, r.response.structureId, Rating::Again, 5);
      if (auto id = progress.recordAnswer(r); !id) {
        *error = id.error().message;
        return;
      }
    }
  };
  std::string ea, eb;
  std::thread a(recorder, attemptA, &ea), b(recorder, attemptB, &eb);
  a.join();
  b.join();
  CHECK(ea.empty());
  CHECK(eb.empty());
  auto db = Database::open(path);
  REQUIRE(db);
  CHECK(countRows(*db, "responses") == 2 * kAnswers);
  auto answered = db->prepare("SELECT answered FROM user_ability WHERE user_id = ?1");
  REQUIRE(answered);
  answered->bind(1, userId);
  REQUIRE(*answered->step());
  CHECK(answered->int64(0) == 2 * kAnswers);
  auto stats = db->prepare("SELECT sum(answered) FROM question_stats");
  REQUIRE(*stats->step());
  CHECK(stats->int64(0) == 2 * kAnswers);
}

TEST_CASE("A review answer is stored with its progress, ability and difficulty in one transaction, outside any attempt") {
  test::TempDir dir;
  Database db = openFresh(dir);
  SqlUserRepository users(db);
  SqlProgressRepository progress(db);
  auto user = users.createUser("eve", Role::Student, "");
  REQUIRE(user);

  ReviewRecord r;
  r.response.userId = user->id;
  r.response.questionId = "toy.ossicles.name_stapes";
  r.response.structureId = "stapes";
  r.response.answer.text = "stirrup'; DROP TABLE review_responses; --";
  r.response.correct = false;
  r.response.score = 0;
  r.response.latencyMs = 6789;
  r.response.render = {"stapes_wdt", "bare", 0.15, 2.1, 0.6};
  r.response.answeredAt = 5000;
  r.update = firstAnswer(user->id, "stapes", Rating::Again, 5000, 1488, 1512);
  auto id = progress.recordReviewAnswer(r);
  REQUIRE_MESSAGE(id, (id ? "" : id.error().message));

  auto back = progress.reviewResponses(user->id);
  REQUIRE(back);
  REQUIRE(back->size() == 1);
  const ReviewResponse& x = (*back)[0];
  CHECK(x.id == *id);
  CHECK(x.userId == user->id);
  CHECK(x.questionId == "toy.ossicles.name_stapes");
  CHECK(x.structureId == "stapes");
  CHECK(x.answer.text == r.response.answer.text);
  CHECK(quiz::answerToJson(x.answer) == quiz::answerToJson(r.response.answer));
  CHECK_FALSE(x.correct);
  CHECK(x.score == 0);
  CHECK(x.latencyMs == 6789);
  CHECK(x.render.presetId == "stapes_wdt");
  CHECK(x.render.mode == "bare");
  CHECK(x.render.t == doctest::Approx(0.15));
  CHECK(x.render.alpha == doctest::Approx(2.1));
  CHECK(x.render.beta == doctest::Approx(0.6));
  CHECK(x.answeredAt == 5000);
  auto p = progress.progress(user->id, "stapes");
  REQUIRE(p->has_value());
  CHECK(((*p)->memory.phase == MemoryPhase::Learning));
  CHECK((*p)->memory.due == 5000 + 60);
  CHECK((*p)->answered == 1);
  CHECK(((*progress.reviewLog(user->id))[0].source == AnswerSource::Review));
  CHECK(*progress.ability(user->id) == std::optional<double>(1488));
  CHECK(*progress.questionDifficulty("toy.ossicles.name_stapes") == std::optional<double>(1512));
  CHECK(countRows(db, "responses") == 0);
  CHECK(progress.reviewResponses(user->id + 1)->empty());

  // A user that does not exist is refused by name, and nothing is written.
  ReviewRecord stranger = r;
  stranger.response.userId = stranger.update.progress.userId = user->id + 100;
  auto refused = progress.recordReviewAnswer(stranger);
  REQUIRE(!refused);
  CHECK(refused.error().message.find("unknown user") != std::string::npos);
  CHECK(countRows(db, "review_responses") == 1);
  CHECK(countRows(db, "memory_states") == 1);
  CHECK(countRows(db, "review_log") == 1);
}

TEST_CASE("A review answer that fails in its last write leaves no trace of its first ones") {
  test::TempDir dir;
  Database db = openFresh(dir);
  SqlUserRepository users(db);
  SqlProgressRepository progress(db);
  auto user = users.createUser("fay", Role::Student, "");
  REQUIRE(user);
  // The question's difficulty is the transaction's last write: make it fail as a full disk would.
  if (db.backend() == Backend::Sqlite) {
    REQUIRE(db.exec("CREATE TRIGGER stats_fail BEFORE INSERT ON question_stats"
                    " BEGIN SELECT RAISE(ABORT, 'database or disk is full'); END"));
  } else {
    REQUIRE(db.exec("CREATE FUNCTION stats_fail() RETURNS trigger LANGUAGE plpgsql AS"
                    " $$ BEGIN RAISE EXCEPTION 'database or disk is full'; END $$;"
                    "CREATE TRIGGER stats_fail BEFORE INSERT ON question_stats FOR EACH ROW EXECUTE FUNCTION stats_fail()"));
  }
  ReviewRecord r;
  r.response.userId = user->id;
  r.response.questionId = "toy.ossicles.name_stapes";
  r.response.structureId = "stapes";
  r.response.answer.text = "stapes";
  r.response.correct = true;
  r.response.score = 1;
  r.response.answeredAt = 7000;
  r.update = firstAnswer(user->id, "stapes", Rating::Good, 7000, 1516, 1484);
  auto failed = progress.recordReviewAnswer(r);
  REQUIRE(!failed);
  CHECK(failed.error().message.find("disk is full") != std::string::npos);
  CHECK(countRows(db, "review_responses") == 0);
  CHECK(countRows(db, "memory_states") == 0);
  CHECK(countRows(db, "review_log") == 0);
  CHECK(countRows(db, "user_ability") == 0);
  CHECK(!progress.ability(user->id)->has_value());

  // Through answerReview the failure is reported and the queue does not move either.
  REQUIRE(storeCourse(db, test::toyCourse(), "toy"));
  SqlCurriculumRepository curriculum(db, test::toyBuiltin());
  test::ToyKeys keys;
  ReviewAnswer review;
  review.userId = user->id;
  review.courseId = "toy";
  review.question = *curriculum.question("toy.ossicles.name_stapes");
  review.answer.text = "Stapes";
  auto grade = answerReview(curriculum, progress, keys, review);
  REQUIRE(!grade);
  CHECK(grade.error().message.find("disk is full") != std::string::npos);
  CHECK(countRows(db, "review_responses") == 0);
  CHECK(countRows(db, "memory_states") == 0);
}

TEST_CASE("answerReview on the store moves the review queue by FSRS: right answers out of it for longer, a wrong one back") {
  test::TempDir dir;
  const std::string path = test::freshDatabase(dir, "q.db");
  {
    Database db = openAt(path);
    REQUIRE(storeCourse(db, test::toyCourse(), "toy"));
  }
  auto db = Database::open(path);
  REQUIRE(db);
  SqlCurriculumRepository curriculum(*db, test::toyBuiltin());
  SqlProgressRepository progress(*db);
  SqlUserRepository users(*db);
  test::ToyKeys keys;
  const std::int64_t userId = users.createUser("gil", Role::Student, "")->id;
  UnixSeconds clock = 2'000'000;
  // Both lessons started: their structures are taught, so review may ask about them.
  REQUIRE(progress.startAttempt(userId, "toy.ossicles", LessonMode::Guided, clock - 100));
  REQUIRE(progress.startAttempt(userId, "toy.middle", LessonMode::Guided, clock - 100));
  EngineOptions options;
  options.clock = [&clock] { return clock; };
  const auto inQueue = [&](UnixSeconds at) {
    auto queue = reviewQueue(curriculum, progress, userId, "toy", at);
    REQUIRE(queue);
    return std::any_of(queue->begin(), queue->end(), [](const StructureProgress& p) { return p.structureId == "stapes"; });
  };
  const auto review = [&](const std::string& questionId, quiz::Answer answer) {
    ReviewAnswer r;
    r.userId = userId;
    r.courseId = "toy";
    auto q = curriculum.question(questionId);
    REQUIRE(q);
    r.question = *q;
    r.answer = std::move(answer);
    r.render = {"stapes_wdt", "wdt", 0.5, 1.6, 1.0};
    r.latencyMs = 900;
    auto grade = answerReview(curriculum, progress, keys, r, options);
    REQUIRE_MESSAGE(grade, (grade ? "" : grade.error().message));
    return *grade;
  };
  quiz::Answer wrongName, rightName, rightRelation;
  wrongName.text = "Incus";
  rightName.text = "stirrup";  // the course's synonym
  const auto relation = quiz::resolveQuestion(*curriculum.question("toy.middle.nearest_to_stapes"), keys);
  REQUIRE(relation);
  rightRelation.choice = relation->keyChoice;

  // Wrong on a first answer: Again, the first learning step (1 minute).
  CHECK_FALSE(review("toy.ossicles.name_stapes", wrongName).correct);
  auto p = *progress.progress(userId, "stapes");
  REQUIRE(p.has_value());
  CHECK((p->memory.phase == MemoryPhase::Learning));
  CHECK(p->memory.due == clock + 60);
  CHECK_FALSE(inQueue(clock));
  clock += 60;
  CHECK(inQueue(clock));

  // Right in under 4 s, the same day: Easy graduates it to Review, due in days; out of the queue
  // now, and a stapes question is no longer chosen.
  CHECK(review("toy.ossicles.name_stapes", rightName).correct);
  p = *progress.progress(userId, "stapes");
  CHECK((p->memory.phase == MemoryPhase::Review));
  CHECK(p->memory.due >= clock + 86400);
  CHECK_FALSE(inQueue(clock));
  auto chosen = chooseReviewQuestion(curriculum, progress, userId, "toy", clock);
  REQUIRE(chosen);
  if (chosen->has_value()) CHECK((*chosen)->target != "stapes");

  // Due again after the interval; right again: a longer interval than the last.
  const UnixSeconds lastInterval = p->memory.due - p->memory.lastReview;
  clock = p->memory.due;
  CHECK(inQueue(clock));
  CHECK(review("toy.middle.nearest_to_stapes", rightRelation).correct);
  p = *progress.progress(userId, "stapes");
  CHECK(p->memory.due - clock > lastInterval);
  CHECK(p->answered == 3);
  CHECK(p->correct == 2);

  // Wrong in Review: a lapse, Relearning for 10 minutes.
  clock = p->memory.due + 10;
  CHECK_FALSE(review("toy.ossicles.name_stapes", wrongName).correct);
  p = *progress.progress(userId, "stapes");
  CHECK((p->memory.phase == MemoryPhase::Relearning));
  CHECK(p->memory.lapses == 1);
  CHECK(p->memory.due == clock + 600);
  auto log = progress.reviewLog(userId);
  REQUIRE(log);
  REQUIRE(log->size() == 4);
  CHECK(((*log)[0].rating == Rating::Again));
  CHECK(((*log)[1].rating == Rating::Easy));
  CHECK(((*log)[3].rating == Rating::Again));
  CHECK(((*log)[3].phaseBefore == MemoryPhase::Review));

  // Every review answer is stored in order, outside any attempt, and moved the Elo ratings.
  auto stored = progress.reviewResponses(userId);
  REQUIRE(stored);
  REQUIRE(stored->size() == 4);
  CHECK((*stored)[0].questionId == "toy.ossicles.name_stapes");
  CHECK((*stored)[2].questionId == "toy.middle.nearest_to_stapes");
  CHECK((*stored)[2].answer.choice == std::optional<int>(relation->keyChoice));
  CHECK((*stored)[1].correct);
  CHECK((*stored)[1].render.mode == "wdt");
  CHECK((*stored)[3].answeredAt == clock);
  CHECK(countRows(*db, "responses") == 0);
  auto answered = db->prepare("SELECT answered FROM user_ability WHERE user_id = ?1");
  REQUIRE(answered);
  answered->bind(1, userId);
  REQUIRE(*answered->step());
  CHECK(answered->int64(0) == 4);
}

TEST_CASE("Exam attempts and their items round-trip; an item's answer is written once, with its learner update") {
  test::TempDir dir;
  Database db = openFresh(dir);
  SqlUserRepository users(db);
  SqlProgressRepository progress(db);
  SqlExamRepository exams(db);
  const std::int64_t userId = users.createUser("ida", Role::Student, "")->id;
  ExamAttempt attempt;
  attempt.userId = userId;
  attempt.examId = "toy.exam";
  attempt.courseId = "toy";
  attempt.startedAt = 1000;
  attempt.deadline = 1600;
  std::vector<ExamItem> items(2);
  items[0].position = 0;
  items[0].question.question.id = "toy.exam.identify.stapes";
  items[0].question.question.kind = quiz::QuestionKind::Identify;
  items[0].question.question.target = "stapes";
  items[0].question.question.prompt = "Which structure is marked?";
  items[0].question.choices = {"incus", "stapes", "malleus"};
  items[0].question.keyChoice = 1;
  items[0].scene = {.structure = "stapes",
                    .presetId = "stapes_wdt",
                    .view = CameraView::Inferior,
                    .camera = std::nullopt,
                    .clip = std::nullopt};
  items[1].position = 1;
  items[1].question.question.id = "toy.exam.locate.incus";
  items[1].question.question.kind = quiz::QuestionKind::Locate;
  items[1].question.question.target = "incus";
  items[1].question.question.prompt = "Locate the Incus on the slice.";
  items[1].locateView = ExamLocateView::Slice;
  items[1].scene = {.structure = "malleus",
                     .presetId = "malleus_wdt",
                     .view = CameraView::LateralRight,
                     .camera = std::nullopt,
                     .clip = std::nullopt};
  auto started = exams.startExamAttempt(attempt, items);
  REQUIRE_MESSAGE(started, (started ? "" : started.error().message));
  CHECK(started->id > 0);
  CHECK(items[1].id > 0);
  auto open = exams.openExamAttempt(userId, "toy.exam");
  REQUIRE(open->has_value());
  CHECK((*open)->deadline == 1600);
  auto back = exams.examItems(started->id);
  REQUIRE(back);
  REQUIRE(back->size() == 2);
  CHECK((*back)[0].question.choices == items[0].question.choices);
  CHECK((*back)[0].question.keyChoice == 1);
  CHECK(((*back)[0].scene.view == CameraView::Inferior));
  CHECK(((*back)[1].locateView == ExamLocateView::Slice));
  CHECK((*back)[1].scene.structure == "malleus");
  CHECK_FALSE((*back)[1].answer.has_value());

  ExamAnswerRecord record;
  record.attemptId = started->id;
  record.position = 1;
  record.answer.questionId = "toy.exam.locate.incus";
  record.answer.structureId = "incus";
  record.answer.answer.pick = quiz::Pick{.structure = "incus", .distanceMm = 0, .pixel = std::nullopt, .view = ""};
  record.answer.correct = true;
  record.answer.score = 1;
  record.answer.latencyMs = 3000;
  record.answer.answeredAt = 1100;
  record.update = firstAnswer(userId, "incus", Rating::Easy, 1100, 1510, 1490);
  REQUIRE(exams.recordExamAnswer(record));
  auto again = exams.recordExamAnswer(record);
  REQUIRE_FALSE(again);
  CHECK(again.error().message.find("already answered") != std::string::npos);
  back = exams.examItems(started->id);
  REQUIRE((*back)[1].answer.has_value());
  CHECK((*back)[1].correct);
  CHECK((*back)[1].latencyMs == 3000);
  auto log = progress.reviewLog(userId);
  REQUIRE(log->size() == 1);
  CHECK(((*log)[0].source == AnswerSource::Exam));
  CHECK((*progress.progress(userId, "incus"))->answered == 1);
  CHECK(*progress.ability(userId) == std::optional<double>(1510));

  REQUIRE(exams.finishExamAttempt(started->id, 1200, 0.5, false));
  CHECK_FALSE(exams.openExamAttempt(userId, "toy.exam")->has_value());
  auto all = exams.examAttempts(userId);
  REQUIRE(all->size() == 1);
  CHECK((*all)[0].passed == std::optional<bool>(false));
  CHECK((*all)[0].score == doctest::Approx(0.5));
  CHECK(exams.courseExamAttempts("toy")->size() == 1);
  CHECK_FALSE(exams.finishExamAttempt(999, 1, 0, std::nullopt));
}
