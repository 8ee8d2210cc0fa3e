// Lesson answers are graded on the class server from the keys its instructor published: the grade
// the laptop sends is never believed. The server's grade equals the laptop's own grader on every
// question kind (random answers, seed printed) but locate, whose pick the laptop measures and the server
// does not believe (without a pixel on the question's view it is practice: test_class_lesson_locate.cpp);
// a student who claims "right" for a wrong answer —
// through her outbox and sync, or with psql itself — has it stored wrong, and class progress says
// so; an answer that does not fit its question is refused and changes nothing; no student reads or
// publishes keys.
#include <doctest/doctest.h>

#include <ctime>
#include <random>
#include <string>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/class_accounts.h"
#include "db/class_lesson_keys.h"
#include "db/sql_repositories.h"
#include "lessons/lesson_engine.h"
#include "quiz/answer_json.h"
#include "secure_class.h"
#include "test_databases.h"
#include "test_support.h"
#include "uuid.h"  // db/src

using namespace at;
using namespace at::db;
using nlohmann::json;

namespace {

using test::openAt;

struct Psql {
  int status = -1;
  std::string output;
};

// psql as the login of `url`, one statement, stopping at the first error.
Psql psql(const std::string& url, const std::string& sql) {
  std::string quoted;
  for (char c : sql) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  Psql r;
  r.output = test::runCommand("psql '" + url + "' -X -q -At -v ON_ERROR_STOP=1 -c '" + quoted + "' 2>&1", r.status);
  return r;
}

std::string sqlText(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

using test::everyServerRow;

struct Toy {
  lessons::Course course = test::toyCourse();
  quiz::GradingContext context = lessons::gradingContext(test::toyStructures(), course);
  std::vector<quiz::ResolvedQuestion> questions;
  Toy() {
    test::ToyKeys keys;
    for (const auto& lesson : course.lessons)
      for (const auto& step : lesson.steps)
        if (step.kind == lessons::StepKind::Question) {
          auto r = quiz::resolveQuestion(step.question, keys);
          REQUIRE(r);
          questions.push_back(*r);
        }
  }
  const quiz::ResolvedQuestion& question(const std::string& id) const {
    for (const auto& q : questions)
      if (q.question.id == id) return q;
    FAIL("no toy question " << id);
    return questions.front();
  }
};

// A random answer of the form `q` takes (sometimes out of range or naming no structure).
quiz::Answer randomAnswer(const quiz::ResolvedQuestion& q, const quiz::GradingContext& context, std::mt19937_64& random) {
  std::vector<std::string> spellings;
  for (const quiz::NameEntry& e : context.names) {
    spellings.push_back(e.structureId);
    spellings.insert(spellings.end(), e.names.begin(), e.names.end());
  }
  spellings.insert(spellings.end(), {"stirrup", "the Stapes", "stapez", "STAPES left", "Incuss", "cochlae", "", "nerve"});
  const auto pickOne = [&](const std::vector<std::string>& from) { return from[random() % from.size()]; };
  quiz::Answer a;
  switch (q.question.kind) {
    case quiz::QuestionKind::Locate: {
      quiz::Pick pick;
      pick.structure = random() % 4 == 0 ? "" : pickOne(spellings);
      if (random() % 2) pick.structure = random() % 2 ? q.question.target : test::toyStructures()[random() % 5].id;
      const double distances[] = {-1, 0, 0.2, 0.5, 0.5 + 1e-7, 0.5 + 1e-3, 3.0};
      pick.distanceMm = distances[random() % 7];
      a.pick = pick;
      break;
    }
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation:
      a.choice = int(random() % (q.choices.size() + 1));  // one past the end now and then
      break;
    case quiz::QuestionKind::Name: a.text = pickOne(spellings); break;
    case quiz::QuestionKind::Order: {
      std::vector<std::string> order;
      const std::size_t n = random() % 5;
      for (std::size_t i = 0; i < n; ++i) {
        if (random() % 3 == 0 && !q.keyOrder.empty()) order.push_back(q.keyOrder[random() % q.keyOrder.size()]);
        else order.push_back(pickOne(spellings));
      }
      if (random() % 3 == 0) order = q.keyOrder;  // the key itself, as ids …
      if (random() % 6 == 0)                      // … or as names
        for (std::string& id : order = q.keyOrder) id = context.displayName(id);
      a.order = order;
      break;
    }
  }
  return a;
}

// The server's grade of `answer` against `key` as the administrator reads it: the score (none:
// practice, not graded), or the refusal's message.
std::variant<std::optional<double>, std::string> serverGrade(Database& admin, const std::string& key,
                                                             const std::string& answer) {
  auto s = admin.prepare("SELECT at_grade_lesson_answer(?1::jsonb, ?2::jsonb)");
  REQUIRE(s);
  s->bind(1, key).bind(2, answer);
  auto row = s->step();
  if (!row) return row.error().message;
  return s->optionalReal(0);
}

std::string answerEventSql(const std::string& code, const std::string& user, const std::string& question,
                           const std::string& answerJson, int claimedCorrect, double claimedScore) {
  const json payload = {{"source", "lesson"}, {"lesson", "toy.ossicles"}, {"question", question},
                        {"answer", json::parse(answerJson)}, {"correct", claimedCorrect == 1}, {"score", claimedScore},
                        {"fsrs_rating", claimedCorrect == 1 ? 4 : 1}};
  return "SELECT at_record_event('" + newUuid() + "', '" + code + "', '" + user + "', 'answer', " +
         std::to_string(std::time(nullptr)) + ", 'toy.ossicles', '" + question + "', 'stapes', " +
         std::to_string(claimedCorrect) + ", " + std::to_string(claimedScore) + ", " + sqlText(payload.dump()) + ")";
}

}  // namespace

TEST_CASE("ClassLessonGrading_TheServerGradesEveryKindOfLessonAnswerAsTheLaptopDoes") {
  auto url = test::freshPostgresDatabase("the lesson grading test");
  if (!url) return;
  Database admin = openAt(*url);
  const std::uint64_t seed = test::freshSeed("ClassLessonGrading_TheServerGradesEveryKindOfLessonAnswerAsTheLaptopDoes");
  std::mt19937_64 random(seed);
  const Toy toy;
  int compared = 0, right = 0, partial = 0, wrong = 0, misfits = 0, practice = 0;
  for (const quiz::ResolvedQuestion& q : toy.questions) {
    const std::string key = lessonKeyJson(q, toy.context);
    for (int i = 0; i < 120; ++i) {
      const quiz::Answer answer = randomAnswer(q, toy.context, random);
      const std::string answerJson = quiz::answerToJson(answer);
      auto laptop = quiz::grade(q, answer, toy.context);
      const auto server = serverGrade(admin, key, answerJson);
      CAPTURE(q.question.id);
      CAPTURE(answerJson);
      if (!laptop) {  // an answer that does not fit: refused on both sides
        CHECK(std::holds_alternative<std::string>(server));
        ++misfits;
        continue;
      }
      CAPTURE(laptop->feedback);
      REQUIRE(std::holds_alternative<std::optional<double>>(server));
      const std::optional<double> score = std::get<std::optional<double>>(server);
      if (q.question.kind == quiz::QuestionKind::Locate) {  // a pick named, not a pixel on the question's view
        CHECK_FALSE(score);
        ++practice;
        continue;
      }
      REQUIRE(score);
      CHECK(*score == doctest::Approx(laptop->score));
      ++compared;
      (laptop->score >= 1 ? right : laptop->score > 0 ? partial : wrong) += 1;
    }
  }
  MESSAGE("seed " << seed << ": " << compared << " answers compared (" << right << " right, " << partial << " partly, "
                  << wrong << " wrong), " << misfits << " refused on both sides, " << practice
                  << " locate picks kept as practice");
  // The answers must have tried every grade, or the comparison proves little.
  CHECK(right > 30);
  CHECK(partial > 3);
  CHECK(wrong > 30);
  CHECK(misfits > 3);
  CHECK(practice > 30);
}

TEST_CASE("ClassLessonGrading_AStudentClaimingRightForWrongAnswersIsGradedByTheServerThroughSyncAndPsql") {
  auto url = test::freshPostgresDatabase("the lesson grading test");
  if (!url) return;
  test::SecureClass c(*url);
  const std::uint64_t seed = test::freshSeed("ClassLessonGrading_AStudentClaimingRightForWrongAnswers");
  std::mt19937_64 random(seed);
  const Toy toy;
  const std::vector<std::string> lessonOne = {"toy.ossicles.name_stapes", "toy.ossicles.identify_incus",
                                              "toy.ossicles.locate_malleus"};

  // Through her laptop's outbox: a real start, then answers of her choosing with the grade she
  // likes written next to them, synced with her own login.
  test::TempDir dir;
  Database laptop = openAt((dir.path() / "sam.db").string());
  REQUIRE(storeCourse(laptop, test::toyCourse(), "toy"));
  SqlUserRepository users(laptop);
  auto user = users.createUser(c.sam, lessons::Role::Student, "");
  REQUIRE(user);
  REQUIRE(rememberMembership(laptop, {c.sam, c.code, c.samUrl, ClassRole::Student}));
  SqlProgressRepository progress(laptop);
  REQUIRE(progress.startAttempt(user->id, "toy.ossicles", lessons::LessonMode::Guided, std::time(nullptr)));
  // At least 40 answers, and until one wrong answer has been sent claimed right (the cheat itself:
  // without one the server's grade could not differ from her claims).
  int laptopRight = 0, sent = 0, wrongSentAsRight = 0, locateSent = 0, locateRight = 0;
  double claimedRight = 0;
  for (int i = 0; i < 40 || wrongSentAsRight == 0; ++i) {
    REQUIRE(i < 2000);
    const quiz::ResolvedQuestion& q = toy.question(lessonOne[random() % lessonOne.size()]);
    quiz::Answer answer = randomAnswer(q, toy.context, random);
    auto laptopGrade = quiz::grade(q, answer, toy.context);
    if (!laptopGrade) continue;  // the laptop never sends those
    laptopRight += laptopGrade->correct ? 1 : 0;
    const bool locate = q.question.kind == quiz::QuestionKind::Locate;  // kept as practice: no pixel
    locateSent += locate ? 1 : 0;
    locateRight += locate && laptopGrade->correct ? 1 : 0;
    // Every wrong answer claimed right; a right one claimed either way.
    const int claimed = !laptopGrade->correct ? 1 : int(random() % 2);
    wrongSentAsRight += laptopGrade->correct || locate ? 0 : 1;
    claimedRight += claimed;
    ++sent;
    const json payload = {{"source", "lesson"}, {"lesson", "toy.ossicles"}, {"question", q.question.id},
                          {"answer", json::parse(quiz::answerToJson(answer))}, {"correct", claimed == 1},
                          {"score", double(claimed)}, {"fsrs_rating", claimed == 1 ? 4 : 1}};
    auto s = laptop.prepare(
        "INSERT INTO outbox (uuid, server, class_code, user_name, kind, occurred_at, lesson_id, question_id, structure,"
        " correct, score, payload) SELECT ?1, server, class_code, user_name, 'answer', ?2, 'toy.ossicles', ?3, ?4, ?5, ?6, ?7"
        " FROM class_memberships");
    REQUIRE(s);
    s->bind(1, newUuid()).bind(2, std::int64_t(std::time(nullptr))).bind(3, q.question.id).bind(4, q.question.target);
    s->bind(5, claimed).bind(6, double(claimed)).bind(7, payload.dump());
    REQUIRE(s->run());
  }
  auto synced = syncOutbox(laptop);
  REQUIRE_MESSAGE(synced, (synced ? "" : synced.error().message));
  REQUIRE(synced->servers.size() == 1);
  CHECK(synced->servers[0].refused == 0);
  CHECK(synced->servers[0].pushed == sent + 1);  // the start and every answer
  MESSAGE("seed " << seed << ": " << sent << " answers sent, " << claimedRight << " claimed right, " << laptopRight
                  << " right by the laptop's own grader, " << wrongSentAsRight << " wrong ones claimed right");

  Database coordinator = openAt(c.coordinatorUrl);
  auto view = classProgress(coordinator, c.code, "");
  REQUIRE(view);
  for (const auto& s : view->students)
    if (s.userName == c.sam) {
      CHECK(s.answers == sent - locateSent);
      CHECK(s.correct == laptopRight - locateRight);  // the server's grades, not her claims
      CHECK(s.practice == locateSent);                // her locate picks: practice, never right
    }
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE user_name = '" + c.sam +
                                       "' AND kind = 'answer' AND (payload::jsonb->>'correct')::boolean <> (correct = 1)") == 0);

  // With psql itself: a wrong answer claimed right is stored wrong; a right one claimed wrong is
  // stored right; the lesson's end takes the server's mean, not the 1.0 she sends.
  int status = 0;
  test::runCommand("psql --version > /dev/null 2>&1", status);
  if (status != 0) {
    test::skipf("the psql part needs psql (Debian package postgresql-client)");
    return;
  }
  const std::int64_t before = test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE correct = 1");
  auto wrongClaimedRight = psql(c.samUrl, answerEventSql(c.code, c.sam, "toy.ossicles.identify_incus", R"({"choice": 0})", 1, 1.0));
  CHECK(wrongClaimedRight.output == "stored\n");
  auto rightClaimedWrong = psql(c.samUrl, answerEventSql(c.code, c.sam, "toy.ossicles.name_stapes", R"({"text": "stirrup"})", 0, 0.0));
  CHECK(rightClaimedWrong.output == "stored\n");
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE correct = 1") == before + 1);
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE question_id = 'toy.ossicles.identify_incus'"
                                   " AND payload LIKE '%\"choice\": 0%' AND correct = 1") == 0);

  // Refused, and nothing anywhere changes: answers that do not fit their question, keys read or published.
  const std::string untouched = everyServerRow(c.admin);
  for (const auto& [question, answer] : std::vector<std::pair<std::string, std::string>>{
           {"toy.ossicles.identify_incus", R"({"choice": 3})"},
           {"toy.ossicles.identify_incus", R"({"choice": 99999999999})"},
           {"toy.ossicles.identify_incus", R"({"text": "incus"})"},
           {"toy.ossicles.name_stapes", R"({"text": "stapes", "choice": 1})"},
           {"toy.ossicles.locate_malleus", R"({"pick": "malleus", "distance_mm": "near"})"},
           {"toy.ossicles.name_stapes", "{}"}}) {
    auto refused = psql(c.samUrl, answerEventSql(c.code, c.sam, question, answer, 1, 1.0));
    CAPTURE(answer);
    CHECK(refused.output.rfind("refused: answer ", 0) == 0);
  }
  auto read = psql(c.samUrl, "SELECT key FROM class_lesson_keys");
  CHECK(read.status != 0);
  CHECK(read.output.find("permission denied") != std::string::npos);
  const json forgedKey = {{"question_id", "toy.ossicles.identify_incus"}, {"kind", "identify"}, {"target", "incus"},
                          {"choices", {"malleus", "incus", "stapes"}}, {"key_choice", 0}};
  auto publish = psql(c.samUrl, "SELECT at_publish_lesson_keys('" + c.code + "', " + sqlText(json::array({forgedKey}).dump()) + ", '')");
  CHECK(publish.status != 0);
  CHECK(publish.output.find("only its instructors and coordinators publish answer keys") != std::string::npos);
  auto grade = psql(c.samUrl, "SELECT at_grade_lesson_answer('{}'::jsonb, '{}'::jsonb)");
  CHECK(grade.status != 0);
  Database sam = openAt(c.samUrl);
  auto viaProgram = publishLessonKeys(sam, c.code, {forgedKey.dump()}, std::nullopt);
  REQUIRE_FALSE(viaProgram);
  CHECK(viaProgram.error().message.find("only its instructors and coordinators") != std::string::npos);
  CHECK(everyServerRow(c.admin) == untouched);
}

TEST_CASE("ClassLessonGrading_AnswersSentBeforeTheKeysAreGradedWhenTheyArePublished_CorrectionsStand_TheLessonEndTakesTheServersMean") {
  auto url = test::freshPostgresDatabase("the lesson grading test");
  if (!url) return;
  test::SecureClass c(*url, false);
  const std::int64_t now = std::int64_t(std::time(nullptr));
  Database sam = openAt(c.samUrl);
  const auto record = [&](const std::string& sql) {
    auto s = sam.prepare(sql);
    REQUIRE(s);
    auto row = s->step();
    REQUIRE_MESSAGE(row, (row ? "" : row.error().message));
    return s->text(0);
  };
  CHECK(record("SELECT at_record_event('" + newUuid() + "', '" + c.code + "', '" + c.sam + "', 'lesson_started', " +
               std::to_string(now) + ", 'toy.ossicles', '', '', NULL, NULL, '{}')") == "stored");
  CHECK(record(answerEventSql(c.code, c.sam, "toy.ossicles.name_stapes", R"({"text": "Stirrup"})", 0, 0.0)) == "stored");
  CHECK(record(answerEventSql(c.code, c.sam, "toy.ossicles.identify_incus", R"({"choice": 2})", 1, 1.0)) == "stored");
  CHECK(record(answerEventSql(c.code, c.sam, "toy.ossicles.locate_malleus",
                              R"({"pick": "incus", "distance_mm": 0.4})", 1, 1.0)) == "stored");
  // No key yet: kept, ungraded (neither her "right" nor anything else).
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE kind = 'answer' AND correct IS NULL") == 3);
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE practice = 1") == 0);

  Database instructor = openAt(c.instructorUrl);
  auto published = publishLessonKeys(instructor, c.code, test::toyLessonKeys(), std::nullopt);
  REQUIRE_MESSAGE(published, (published ? "" : published.error().message));
  CHECK(*published == 6);
  // Graded now: "Stirrup" is a synonym (right), choice 2 is the stapes (wrong); the click the laptop
  // says was 0.4 mm from the malleus came without a pixel on the question's view: practice.
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE kind = 'answer' AND correct IS NULL") == 1);
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE kind = 'answer' AND correct = 1") == 1);
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE question_id = 'toy.ossicles.locate_malleus'"
                                   " AND practice = 1 AND correct IS NULL AND score IS NULL") == 1);
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_audit WHERE action = 'lesson_keys' AND actor = '" +
                                       c.instructor + "' AND target = '6 questions'") == 1);

  // A coordinator's correction stands when the keys are published again, even with a changed key;
  // answers without one follow the new key.
  std::string identifyUuid;
  {
    auto s = c.admin.prepare("SELECT uuid FROM class_events WHERE question_id = 'toy.ossicles.identify_incus'");
    REQUIRE(s);
    REQUIRE(*s->step());
    identifyUuid = s->text(0);
  }
  Database coordinator = openAt(c.coordinatorUrl);
  REQUIRE(correctClassEvent(coordinator, identifyUuid, false, 0.5, "half credit: the stapes touches the incus", std::nullopt));
  std::vector<std::string> changed = test::toyLessonKeys();
  for (std::string& k : changed) {
    json key = json::parse(k);
    if (key["question_id"] == "toy.ossicles.identify_incus") key["key_choice"] = 2;
    if (key["question_id"] == "toy.ossicles.locate_malleus") key["tolerance_mm"] = 0.1;
    k = key.dump();
  }
  REQUIRE(publishLessonKeys(instructor, c.code, changed, std::nullopt));
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE uuid = '" + identifyUuid +
                                       "' AND correct = 0 AND score = 0.5") == 1);
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE question_id = 'toy.ossicles.locate_malleus'"
                                   " AND practice = 1 AND correct IS NULL") == 1);  // still practice
  REQUIRE(publishLessonKeys(instructor, c.code, test::toyLessonKeys(), std::nullopt));

  // (at the time it is recorded, as the laptop sends it: after the answers, which carry theirs; the
  // start's `now` could lie a second before them, and the end is scored from the answers up to it)
  CHECK(record("SELECT at_record_event('" + newUuid() + "', '" + c.code + "', '" + c.sam + "', 'lesson_finished', " +
               std::to_string(std::time(nullptr)) + ", 'toy.ossicles', '', '', NULL, 1.0, '{\"score\": 1.0}')") == "stored");
  // The lesson's end: the mean of the server's grades (1, the corrected 0.5; the practice pick left
  // out), not her 1.0.
  auto end = c.admin.prepare("SELECT score, payload FROM class_events WHERE kind = 'lesson_finished'");
  REQUIRE(end);
  REQUIRE(*end->step());
  CHECK(end->real(0) == doctest::Approx(1.5 / 2.0));
  CHECK(json::parse(end->text(1))["score"].get<double>() == doctest::Approx(1.5 / 2.0));
}
