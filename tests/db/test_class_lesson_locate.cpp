// Lesson locate answers on a class server: the laptop measures a click from its own copy of the
// dataset, so the server never believes the pick an answer names. A pixel picked on the question's
// fixed view (the view's id and size are in the published key, with the pixels whose click counts)
// is graded there from the pixel alone; every other locate answer — a forged "right" pick, a pick
// on a view the key does not hold — is kept as practice, and neither `class progress` nor
// analytics counts it. Tried as the student's own login, through her program, her outbox and psql.
#include <doctest/doctest.h>

#include <ctime>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/analytics_store.h"
#include "db/class_server.h"
#include "db/sql_repositories.h"
#include "secure_class.h"
#include "test_databases.h"
#include "test_support.h"
#include "toy_course.h"
#include "uuid.h"  // db/src

using namespace at;
using namespace at::db;
using nlohmann::json;

namespace {

using test::openAt;

// A fixed view of the toy locate question as a key holds it: its size, id and accepted runs.
struct View {
  std::string id;
  int width = 0, height = 0;
  std::vector<std::array<int, 3>> runs;  // y, x_from, x_to
  bool accepts(int x, int y) const {
    for (const auto& r : runs)
      if (r[0] == y && x >= r[1] && x <= r[2]) return true;
    return false;
  }
  json toJson() const {
    json list = json::array();
    for (const auto& r : runs) list.push_back({r[0], r[1], r[2]});
    return {{"view", id}, {"width", width}, {"height", height}, {"runs", list}};
  }
};

// A random view: one or two runs on some rows, never the whole picture; at least one run.
View randomView(std::mt19937_64& random, const std::string& id) {
  View v;
  v.id = id;
  v.width = 8 + int(random() % 200);
  v.height = 6 + int(random() % 150);
  for (int y = 0; y < v.height; ++y) {
    if (random() % 3) continue;
    const int a = int(random() % (v.width - 1)), b = a + int(random() % (v.width - 1 - a));
    v.runs.push_back({y, a, b});
    if (b + 4 <= v.width && random() % 2) v.runs.push_back({y, b + 2, b + 2 + int(random() % (v.width - b - 3))});
  }
  if (v.runs.empty()) v.runs.push_back({int(random() % v.height), 0, int(random() % (v.width - 1))});
  return v;
}

std::string sqlText(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string eventSql(const std::string& uuid, const std::string& code, const std::string& user, const std::string& kind,
                     std::int64_t at, const std::string& question, const json& answer, int claimed) {
  const json payload = kind == "answer"
                           ? json{{"source", "lesson"}, {"lesson", "toy.ossicles"}, {"question", question},
                                  {"answer", answer}, {"correct", claimed == 1}, {"score", double(claimed)},
                                  {"fsrs_rating", claimed == 1 ? 4 : 1}}
                           : json{{"score", 1.0}};
  return "SELECT at_record_event('" + uuid + "', '" + code + "', '" + user + "', '" + kind + "', " +
         std::to_string(at) + ", 'toy.ossicles', '" + question + "', 'malleus', " +
         (kind == "answer" ? std::to_string(claimed) + ", " + std::to_string(double(claimed)) : std::string("NULL, 1.0")) +
         ", " + sqlText(payload.dump()) + ")";
}

std::string recordAs(Database& login, const std::string& sql) {
  auto s = login.prepare(sql);
  REQUIRE(s);
  auto row = s->step();
  REQUIRE_MESSAGE(row, (row ? "" : row.error().message));
  return s->text(0);
}

enum class Sent { Graded, Practice, Refused };

}  // namespace

TEST_CASE("ClassLessonLocate_AForgedRightPickIsPracticeNotCounted_APixelPickedOnTheQuestionsViewIsGradedByTheServer") {
  auto url = test::freshPostgresDatabase("the lesson locate test");
  if (!url) return;
  test::SecureClass c(*url, false);
  const std::uint64_t seed = test::freshSeed("ClassLessonLocate_AForgedRightPick");
  std::mt19937_64 random(seed);
  const std::string locateId = "toy.ossicles.locate_malleus";

  // The instructor publishes the keys; the locate key holds two fixed views of the question.
  const View first = randomView(random, "400x300-" + std::to_string(random())),
             second = randomView(random, "400x300-" + std::to_string(random()));
  std::vector<std::string> keys = test::toyLessonKeys();
  int identifyKey = -1;
  for (std::string& k : keys) {
    json key = json::parse(k);
    if (key["question_id"] == locateId) key["views"] = json::array({first.toJson(), second.toJson()});
    if (key["question_id"] == "toy.ossicles.identify_incus") identifyKey = key["key_choice"].get<int>();
    k = key.dump();
  }
  REQUIRE(identifyKey >= 0);
  Database instructor = openAt(c.instructorUrl);
  auto published = publishLessonKeys(instructor, c.code, keys, std::nullopt);
  REQUIRE_MESSAGE(published, (published ? "" : published.error().message));

  Database sam = openAt(c.samUrl);
  std::int64_t clock = std::int64_t(std::time(nullptr)) - 5000;  // one second apart: "latest" is well defined
  REQUIRE(recordAs(sam, eventSql(newUuid(), c.code, c.sam, "lesson_started", clock++, "", json(), 0)) == "stored");

  // Her answers, every one claimed right: the first seven try each way of answering once, the rest
  // are drawn. What the server must do with each is known from the view she names.
  std::map<std::string, Sent> sent;  // uuid → what the server must do
  std::map<std::string, int> expectedGrade;
  int graded = 0, right = 0, practice = 0, refused = 0, lastGrade = -1;
  const int answers = 40 + int(random() % 40);
  for (int i = 0; i < answers; ++i) {
    const int way = i < 7 ? i : int(random() % 7);
    const View& view = random() % 2 ? first : second;
    json answer = {{"pick", "malleus"}, {"distance_mm", 0.0}};  // what a forger claims
    Sent expect = Sent::Graded;
    int x = int(random() % view.width), y = int(random() % view.height);
    switch (way) {
      case 0:  // a pixel anywhere on the view; the first in its last column, where no run reaches
        if (i == 0) x = view.width - 1;
        break;
      case 1: {       // a right pick: a pixel inside one of the view's runs
        const auto& r = view.runs[random() % view.runs.size()];
        y = r[0];
        x = r[1] + int(random() % (r[2] - r[1] + 1));
        break;
      }
      case 2: expect = Sent::Practice; break;  // the forgery: "malleus, 0 mm" with no pixel
      case 3:                                   // a pixel on a view the key does not hold
        expect = Sent::Practice;
        answer["view"] = "400x300-" + std::to_string(random());
        answer["pixel"] = {x, y};
        break;
      case 4:  // outside the picture
        expect = Sent::Refused;
        if (random() % 2) x = random() % 2 ? -1 - int(random() % 5) : view.width + int(random() % 5);
        else y = random() % 2 ? -1 - int(random() % 5) : view.height + int(random() % 5);
        break;
      case 5:  // not whole pixels, or not a pair
        expect = Sent::Refused;
        answer["view"] = view.id;
        answer["pixel"] = random() % 2 ? json{x + 0.5, y} : json{x, y, 0};
        break;
      case 6:  // a pixel without its view
        expect = Sent::Refused;
        answer["pixel"] = {x, y};
        break;
    }
    if (way <= 1 || way == 4) {
      answer["view"] = view.id;
      answer["pixel"] = {x, y};
    }
    const std::string uuid = newUuid();
    CAPTURE(answer.dump());
    const std::string result = recordAs(sam, eventSql(uuid, c.code, c.sam, "answer", clock++, locateId, answer, 1));
    if (expect == Sent::Refused) {
      CHECK(result.rfind("refused: answer " + uuid, 0) == 0);
      ++refused;
      continue;
    }
    CHECK(result == "stored");
    sent[uuid] = expect;
    if (expect == Sent::Practice) {
      ++practice;
      continue;
    }
    expectedGrade[uuid] = view.accepts(x, y) ? 1 : 0;
    ++graded;
    right += expectedGrade[uuid];
    lastGrade = expectedGrade[uuid];
  }
  REQUIRE(right >= 1);  // way 1 made one
  REQUIRE(graded > right);  // and a wrong one (the first answer: no run reaches the last column)
  MESSAGE("seed " << seed << ": " << answers << " locate answers: " << graded << " graded (" << right << " right), "
                  << practice << " practice, " << refused << " refused");

  // Her forgery through her laptop's outbox and sync: stored, as practice.
  test::TempDir dir;
  Database laptop = openAt((dir.path() / "sam.db").string());
  REQUIRE(rememberMembership(laptop, {c.sam, c.code, c.samUrl, ClassRole::Student}));
  {
    const std::string uuid = newUuid();
    const json payload = {{"source", "lesson"}, {"lesson", "toy.ossicles"}, {"question", locateId},
                          {"answer", {{"pick", "malleus"}, {"distance_mm", 0.1}}}, {"correct", true}, {"score", 1.0}};
    auto s = laptop.prepare(
        "INSERT INTO outbox (uuid, server, class_code, user_name, kind, occurred_at, lesson_id, question_id, structure,"
        " correct, score, payload) SELECT ?1, server, class_code, user_name, 'answer', ?2, 'toy.ossicles', ?3, 'malleus',"
        " 1, 1.0, ?4 FROM class_memberships");
    REQUIRE(s);
    s->bind(1, uuid).bind(2, clock++).bind(3, locateId).bind(4, payload.dump());
    REQUIRE(s->run());
    auto synced = syncOutbox(laptop);
    REQUIRE_MESSAGE(synced, (synced ? "" : synced.error().message));
    CHECK(synced->servers.at(0).pushed == 1);
    CHECK(synced->servers.at(0).refused == 0);
    sent[uuid] = Sent::Practice;
    ++practice;
  }
  // And with psql itself.
  int status = 0;
  test::runCommand("psql --version > /dev/null 2>&1", status);
  if (status == 0) {
    const std::string uuid = newUuid();
    const std::string sql = eventSql(uuid, c.code, c.sam, "answer", clock++, locateId, {{"pick", "malleus"}}, 1);
    std::string quoted;
    for (char ch : sql) quoted += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
    const std::string out = test::runCommand("psql '" + c.samUrl + "' -X -q -At -v ON_ERROR_STOP=1 -c '" + quoted + "' 2>&1", status);
    CHECK(status == 0);
    CHECK(out == "stored\n");
    sent[uuid] = Sent::Practice;
    ++practice;
  }

  // Every stored answer as the server must have it.
  for (const auto& [uuid, expect] : sent) {
    CAPTURE(uuid);
    auto row = c.admin.prepare("SELECT correct, score, practice, payload FROM class_events WHERE uuid = ?1");
    REQUIRE(row);
    row->bind(1, uuid);
    REQUIRE(*row->step());
    const json payload = json::parse(row->text(3));
    if (expect == Sent::Practice) {
      CHECK(row->isNull(0));
      CHECK(row->isNull(1));
      CHECK(row->integer(2) == 1);
      CHECK_FALSE(payload.contains("correct"));
      CHECK(payload.value("practice", std::string()).find("practice") != std::string::npos);
    } else {
      CHECK(row->integer(0) == expectedGrade[uuid]);
      CHECK(row->real(1) == double(expectedGrade[uuid]));
      CHECK(row->integer(2) == 0);
      CHECK(payload["correct"].get<bool>() == (expectedGrade[uuid] == 1));
    }
  }
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE kind = 'answer'") == graded + practice);

  // The class view: her graded answers and the right ones among them; practice apart, never right.
  Database coordinator = openAt(c.coordinatorUrl);
  auto view = classProgress(coordinator, c.code, "");
  REQUIRE_MESSAGE(view, (view ? "" : view.error().message));
  bool seen = false;
  for (const auto& s : view->students)
    if (s.userName == c.sam) {
      seen = true;
      CHECK(s.answers == graded);
      CHECK(s.correct == right);
      CHECK(s.practice == practice);
      CHECK(s.ungraded == 0);
    }
  CHECK(seen);
  for (const auto& s : view->structures)
    if (s.structureId == "malleus") CHECK(s.correct == right);
  SqlCurriculumRepository curriculum(c.admin, test::toyBuiltin());  // analytics on a server: the owner's login
  auto input = loadAnalyticsInput(c.admin, curriculum, test::toyCourse().id, c.code);
  REQUIRE_MESSAGE(input, (input ? "" : input.error().message));
  int analyticsAnswers = 0, analyticsRight = 0;
  for (const auto& a : input->answers) {
    analyticsAnswers += 1;
    analyticsRight += a.correct ? 1 : 0;
  }
  CHECK(analyticsAnswers == graded);
  CHECK(analyticsRight == right);

  // The lesson's end: the other two answered right, then her 1.0 claim is replaced by the mean of
  // the latest graded answers (the latest graded locate one; practice left out).
  REQUIRE(recordAs(sam, eventSql(newUuid(), c.code, c.sam, "answer", clock++, "toy.ossicles.name_stapes",
                                 {{"text", "stapes"}}, 1)) == "stored");
  REQUIRE(recordAs(sam, eventSql(newUuid(), c.code, c.sam, "answer", clock++, "toy.ossicles.identify_incus",
                                 {{"choice", identifyKey}}, 1)) == "stored");
  REQUIRE(recordAs(sam, eventSql(newUuid(), c.code, c.sam, "answer", clock++, locateId, {{"pick", "malleus"}}, 1)) ==
          "stored");  // a practice answer after the graded ones: left out
  REQUIRE(recordAs(sam, eventSql(newUuid(), c.code, c.sam, "lesson_finished", clock++, "", json(), 0)) == "stored");
  auto end = c.admin.prepare("SELECT score, payload FROM class_events WHERE kind = 'lesson_finished'");
  REQUIRE(end);
  REQUIRE(*end->step());
  CHECK(end->real(0) == doctest::Approx((2.0 + lastGrade) / 3.0));
  CHECK(json::parse(end->text(1))["score"].get<double>() == doctest::Approx((2.0 + lastGrade) / 3.0));

  // Published again with every run moved one row down: the pixel answers are graded again from the
  // new runs; practice stays practice.
  View firstMoved = first, secondMoved = second;
  for (View* v : {&firstMoved, &secondMoved})
    for (auto& r : v->runs) r[0] = (r[0] + 1) % v->height;
  for (std::string& k : keys) {
    json key = json::parse(k);
    if (key["question_id"] == locateId) key["views"] = json::array({firstMoved.toJson(), secondMoved.toJson()});
    k = key.dump();
  }
  REQUIRE(publishLessonKeys(instructor, c.code, keys, std::nullopt));
  int rightNow = 0;
  {
    auto rows = c.admin.prepare("SELECT payload::jsonb->'answer', correct, practice FROM class_events"
                                " WHERE question_id = ?1 AND kind = 'answer'");
    REQUIRE(rows);
    rows->bind(1, locateId);
    while (*rows->step()) {
      const json a = json::parse(rows->text(0));
      const bool onView = a.contains("view") && (a["view"] == first.id || a["view"] == second.id);
      CAPTURE(a.dump());
      CHECK(rows->integer(2) == (onView ? 0 : 1));
      if (!onView) continue;
      const View& v = a["view"] == first.id ? firstMoved : secondMoved;
      const int expected = v.accepts(a["pixel"][0].get<int>(), a["pixel"][1].get<int>()) ? 1 : 0;
      CHECK(rows->integer(1) == expected);
      rightNow += expected;
    }
  }
  CHECK(test::scalarCount(c.admin, "SELECT COUNT(*) FROM class_events WHERE practice = 1") == practice + 1);
  MESSAGE("after the keys changed: " << rightNow << " right of " << graded << " graded");
}

TEST_CASE("ClassLessonLocate_ClassProgressAndAnalyticsLeavePracticeAndWaitingAnswersOutOfTheRightShare") {
  test::TempDir dir;
  const std::string location = test::freshDatabase(dir, "server.db");
  Database server = openAt(location);
  const std::uint64_t seed = test::freshSeed("ClassLessonLocate_ClassProgressAndAnalyticsLeavePracticeAndWaitingAnswersOutOfTheRightShare");
  std::mt19937_64 random(seed);
  REQUIRE(storeCourse(server, test::toyCourse(), "toy"));
  auto made = createClass(server, "Ear anatomy", "dr_ada");
  REQUIRE(made);
  const std::vector<std::string> names = {"ann", "ben", "cat"};
  for (const std::string& n : names) REQUIRE(joinClass(server, made->code, n));
  // Random answers written as a server stores them: graded, waiting for a key, or practice (every
  // kind at least once for each student, so each count is tested).
  std::map<std::string, std::array<int, 4>> expected;  // graded answers, right, waiting, practice
  std::map<std::string, std::set<std::string>> structuresOf;  // of the graded answers
  const std::vector<std::pair<std::string, std::string>> questions = {
      {"toy.ossicles.name_stapes", "stapes"}, {"toy.ossicles.identify_incus", "incus"}, {"toy.ossicles.locate_malleus", "malleus"}};
  std::int64_t at = std::int64_t(std::time(nullptr)) - 1000;
  for (const std::string& n : names) {
    const int count = 4 + int(random() % 20);
    for (int i = 0; i < count; ++i) {
      const int state = i < 4 ? i : int(random() % 4);  // 0 right, 1 wrong, 2 waiting, 3 practice
      const auto& [question, structure] = questions[state == 3 ? 2 : random() % 3];
      auto s = server.prepare(
          "INSERT INTO class_events (uuid, class_code, user_name, kind, occurred_at, lesson_id, question_id, structure,"
          " correct, score, payload, received_at, practice) VALUES (?1, ?2, ?3, 'answer', ?4, 'toy.ossicles', ?5, ?6, ?7, ?8, '{}', ?4, ?9)");
      REQUIRE(s);
      s->bind(1, newUuid()).bind(2, made->code).bind(3, n).bind(4, at++).bind(5, question).bind(6, structure);
      s->bind(7, state <= 1 ? std::optional<std::int64_t>(state == 0 ? 1 : 0) : std::nullopt);
      s->bind(8, state <= 1 ? std::optional<double>(state == 0 ? 1.0 : 0.0) : std::nullopt);
      s->bind(9, state == 3 ? 1 : 0);
      REQUIRE(s->run());
      if (state <= 1) structuresOf[n].insert(structure);
      auto& e = expected[n];
      e[0] += state <= 1;
      e[1] += state == 0;
      e[2] += state == 2;
      e[3] += state == 3;
    }
  }
  INFO("seed " << seed);
  auto progress = classProgress(server, made->code, "dr_ada");
  REQUIRE_MESSAGE(progress, (progress ? "" : progress.error().message));
  REQUIRE(progress->students.size() == names.size());
  for (const auto& p : progress->students) {
    CAPTURE(p.userName);
    const auto& e = expected.at(p.userName);
    CHECK(p.answers == e[0]);
    CHECK(p.correct == e[1]);
    CHECK(p.ungraded == e[2]);
    CHECK(p.practice == e[3]);
    CHECK(p.structures == int(structuresOf[p.userName].size()));
  }
  SqlCurriculumRepository curriculum(server, test::toyBuiltin());
  auto input = loadAnalyticsInput(server, curriculum, test::toyCourse().id, made->code);
  REQUIRE_MESSAGE(input, (input ? "" : input.error().message));
  std::map<std::int64_t, std::string> nameOf;
  for (const auto& u : input->students) nameOf[u.id] = u.name;
  std::map<std::string, std::array<int, 2>> seen;
  for (const auto& a : input->answers) {
    seen[nameOf.at(a.userId)][0] += 1;
    seen[nameOf.at(a.userId)][1] += a.correct ? 1 : 0;
  }
  int waiting = 0;
  for (const std::string& n : names) {
    CAPTURE(n);
    CHECK(seen[n][0] == expected.at(n)[0]);
    CHECK(seen[n][1] == expected.at(n)[1]);
    waiting += expected.at(n)[2];
  }
  CHECK(input->waitingAnswers == waiting);
}
