// Graded exams on a class server, tried as a student would cheat with her own login: the keys
// cannot be read, a grade cannot be written or forged, and a refused attempt changes nothing;
// the server's grades match the keys, and the class's progress shows the exam.
#include <doctest/doctest.h>

#include <array>
#include <cstdio>
#include <ctime>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/class_exams.h"
#include "secure_class.h"
#include "uuid.h"  // db/src, as the outbox mints event ids
#include "test_support.h"

using namespace at;
using namespace at::db;

namespace {

using test::openAt;
using test::SecureClass;
std::int64_t count(Database& db, const std::string& sql) { return test::scalarCount(db, sql); }

// The keys of toyExam's items, one maker a kind. The name key leaves what setNameKey fills empty.
ClassExamKey identifyKey(const std::string& questionId, const std::string& target, int keyChoice) {
  ClassExamKey k;
  k.questionId = questionId;
  k.target = target;
  k.keyChoice = keyChoice;
  return k;
}
ClassExamKey nameKey(const std::string& questionId, const std::string& target, std::vector<std::string> names) {
  ClassExamKey k;
  k.questionId = questionId;
  k.target = target;
  k.names = std::move(names);
  return k;
}
ClassExamKey locateKey(const std::string& questionId, const std::string& target, double toleranceMm,
                       std::vector<PixelRun> acceptedPixels) {
  ClassExamKey k;
  k.questionId = questionId;
  k.target = target;
  k.toleranceMm = toleranceMm;
  k.acceptedPixels = std::move(acceptedPixels);
  return k;
}

// An exam of every kind: two identify items (keys 2 and 0), a name item, a locate item on a 40×30
// picture whose pixels (5..9, 10) and (6..8, 11) count. Item texts never name an identify or name
// item's target.
ClassExamOpening toyExam(const std::string& id) {
  ClassExamOpening x;
  x.examId = id;
  x.courseId = "toy";
  x.title = "Ossicles exam";
  x.timeLimitS = 600;
  x.passScore = 0.5;
  x.items = {{0, "identify", "Which structure is marked?", {"malleus", "incus", "stapes", "cochlea"}, "3d", "{}", "iVBORw0KGgo="},
             {1, "name", "Name the marked structure.", {}, "3d", "{}", "iVBORw0KGgo="},
             {2, "locate", "Locate the incus.", {}, "3d", R"({"structure":"malleus","preset":"malleus_wdt"})", "iVBORw0KGgo=",
              40, 30},
             {3, "identify", "Which structure is marked?", {"cochlea", "malleus", "incus", "stapes"}, "3d", "{}", "iVBORw0KGgo="}};
  x.keys = {identifyKey("ex.identify.stapes", "stapes", 2), nameKey("ex.name.stapes", "stapes", {"Stapes", "stirrup"}),
            locateKey("ex.locate.incus", "incus", 2.0, {{10, 5, 9}, {11, 6, 8}}),
            identifyKey("ex.identify.cochlea", "cochlea", 0)};
  return x;
}

// Every row of the exam tables, as the administrator reads them: compared before and after a
// refused operation.
std::string examTables(Database& admin) {
  std::string out;
  for (const char* table : {"class_exams", "class_exam_items", "class_exam_keys", "class_exam_locate_keys",
                            "class_exam_sittings", "class_exam_answers", "class_audit"}) {
    auto s = admin.prepare(std::string("SELECT t::text FROM ") + table + " t ORDER BY t::text");
    REQUIRE(s);
    out += std::string(table) + ":\n";
    while (*s->step()) out += s->text(0) + "\n";
  }
  return out;
}

// The status, with its error's message when it failed (for the failure report).
std::string messageOf(const Status& s) { return s ? "ok" : s.error().message; }

bool refusedForRights(const Error& e) {
  return e.message.find("permission denied") != std::string::npos;
}

}  // namespace

TEST_CASE("ClassExam_KeysNeverReachAStudent_GradesAreTheServersAndForgeriesChangeNothing") {
  auto url = test::freshPostgresDatabase("the class exam test");
  if (!url) return;
  SecureClass c(*url);
  Database instructor = openAt(c.instructorUrl);
  Database eve = openAt(c.eveUrl);
  Database sam = openAt(c.samUrl);

  // A student cannot open an exam; the instructor can, once.
  CHECK_FALSE(openClassExam(eve, c.code, toyExam("ex"), std::nullopt));
  auto opened = openClassExam(instructor, c.code, toyExam("ex"), std::nullopt);
  REQUIRE_MESSAGE(opened, (opened ? "" : opened.error().message));
  CHECK(*opened == 4);
  CHECK_FALSE(openClassExam(instructor, c.code, toyExam("ex"), std::nullopt));

  // The keys: no SELECT on their table, and no column a student can read says what is right.
  for (const std::string sql : {"SELECT * FROM class_exam_keys", "SELECT key_choice FROM class_exam_keys",
                                "SELECT count(*) FROM class_exam_keys", "SELECT * FROM class_exam_locate_keys",
                                "SELECT count(*) FROM class_exam_locate_keys WHERE y = 10"}) {
    CAPTURE(sql);
    auto s = eve.prepare(sql);
    REQUIRE(s);
    auto row = s->step();
    REQUIRE_FALSE(row);
    CHECK(refusedForRights(row.error()));
  }
  CHECK(count(c.admin, "SELECT count(*) FROM information_schema.columns WHERE table_schema = current_schema()"
                       " AND column_name IN ('target', 'key_choice', 'names', 'tolerance_mm', 'y', 'x_from', 'x_to')"
                       " AND table_name LIKE 'class\\_exam%'"
                       " AND has_column_privilege('" + c.eve + "', table_name, column_name, 'SELECT')") == 0);
  // What the student's machine receives: the items without a word of their keys.
  auto sitting = startClassExam(eve, c.code, "ex", std::nullopt);
  REQUIRE_MESSAGE(sitting, (sitting ? "" : sitting.error().message));
  REQUIRE(sitting->items.size() == 4);
  CHECK(sitting->deadline - sitting->serverNow > 590);
  for (const ClassExamItem& item : sitting->items)
    if (item.kind != "locate")
      for (const char* secret : {"stapes", "Stapes", "stirrup"}) {
        CHECK(item.prompt.find(secret) == std::string::npos);
        CHECK(item.sceneJson.find(secret) == std::string::npos);
      }

  // Forged grades, as the student login: each refused, and nothing changed at all.
  CHECK(messageOf(answerClassExam(eve, c.code, "ex", 0, {0, std::nullopt, std::nullopt, 900}, std::nullopt)) == "ok");
  const std::string before = examTables(c.admin);
  const std::vector<std::string> forgeries = {
      "INSERT INTO class_exam_answers (class_code, exam_id, user_name, position, answer, correct, score, answered_at)"
      " VALUES ('" + c.code + "', 'ex', '" + c.eve + "', 1, '{}', 1, 1, 0)",
      "UPDATE class_exam_answers SET correct = 1, score = 1",
      "UPDATE class_exam_sittings SET score = 1, passed = 1",
      "DELETE FROM class_exam_answers",
      "UPDATE class_exam_keys SET key_choice = 0",
      "SELECT at_hand_in('" + c.code + "', 'ex', '" + c.eve + "')",
      "SELECT at_open_sitting('" + c.code + "', 'ex', '" + c.eve + "')",
      "SELECT at_exam_name('x')",
      // Answering again over a wrong answer, or for another student, or as another student:
      "SELECT at_answer_exam('" + c.code + "', 'ex', 0, 2, NULL, NULL, NULL, 0, '')",
      "SELECT at_answer_exam('" + c.code + "', 'ex', 1, NULL, 'stapes', NULL, NULL, 0, '" + c.sam + "')",
      "SELECT at_finish_exam('" + c.code + "', 'ex', '" + c.sam + "')",
      "SELECT at_close_exam('" + c.code + "', 'ex', '')",
      // An answer of the wrong form, an item that is not there:
      "SELECT at_answer_exam('" + c.code + "', 'ex', 1, 2, NULL, NULL, NULL, 0, '')",
      "SELECT at_answer_exam('" + c.code + "', 'ex', 3, 7, NULL, NULL, NULL, 0, '')",
      "SELECT at_answer_exam('" + c.code + "', 'ex', 9, 0, NULL, NULL, NULL, 0, '')",
      // A locate item: the structure "picked" (the laptop's say, as before), a grade, a pixel off
      // the picture, a pixel with a choice:
      "SELECT at_answer_exam('" + c.code + "', 'ex', 2, NULL, NULL, 'incus', 0.5::double precision, 0, '')",
      "SELECT at_answer_exam('" + c.code + "', 'ex', 2, NULL, 'incus', NULL, NULL, 0, '')",
      "SELECT at_answer_exam('" + c.code + "', 'ex', 2, NULL, NULL, 40, 10, 0, '')",
      "SELECT at_answer_exam('" + c.code + "', 'ex', 2, NULL, NULL, 7, -1, 0, '')",
      "SELECT at_answer_exam('" + c.code + "', 'ex', 2, 1, NULL, 7, 10, 0, '')",
      "INSERT INTO class_exam_locate_keys VALUES ('" + c.code + "', 'ex', 2, 0, 0, 39)"};
  for (const std::string& sql : forgeries) {
    CAPTURE(sql);
    auto s = eve.prepare(sql);
    REQUIRE(s);
    auto row = s->step();
    CHECK_FALSE(row);
    CHECK(examTables(c.admin) == before);
  }
  // Before handing in she cannot read her own grades; sam sees nothing of hers.
  CHECK(count(eve, "SELECT count(*) FROM class_exam_answers") == 0);
  CHECK(count(sam, "SELECT count(*) FROM class_exam_sittings") == 0);
  CHECK(startClassExam(eve, c.code, "ex", std::nullopt)->answered == std::set<int>{0});

  CHECK(messageOf(answerClassExam(eve, c.code, "ex", 1, {std::nullopt, "  the STIRRUP ", std::nullopt, 0},
                                  std::nullopt)) == "ok");
  CHECK(messageOf(answerClassExam(eve, c.code, "ex", 2, {std::nullopt, std::nullopt, std::array<int, 2>{9, 10}, 0},
                                  std::nullopt)) == "ok");
  auto result = finishClassExam(eve, c.code, "ex", std::nullopt);
  REQUIRE_MESSAGE(result, (result ? "" : result.error().message));
  // Wrong choice, right name (case, spaces and "the" ignored), a click on a pixel that counts, unanswered.
  CHECK(result->score == doctest::Approx(0.5));
  CHECK(result->passed == std::optional<bool>(true));
  REQUIRE(result->items.size() == 4);
  CHECK((result->items[0].answered && !result->items[0].correct));
  CHECK(result->items[1].correct);
  CHECK(result->items[2].correct);
  CHECK_FALSE(result->items[3].answered);
  CHECK(count(eve, "SELECT count(*) FROM class_exam_answers") == 3);
  // After handing in: nothing more is graded, and a new start says so.
  CHECK(startClassExam(eve, c.code, "ex", std::nullopt)->handedIn);
  CHECK_FALSE(sitting->handedIn);
  CHECK_FALSE(answerClassExam(eve, c.code, "ex", 3, {0, std::nullopt, std::nullopt, 0}, std::nullopt));

  // The class's progress shows the exam; closing hands sam's open sitting in; both are audited.
  CHECK(startClassExam(sam, c.code, "ex", std::nullopt));
  auto closed = closeClassExam(instructor, c.code, "ex", std::nullopt);
  REQUIRE_MESSAGE(closed, (closed ? "" : closed.error().message));
  CHECK(*closed == 1);
  CHECK_FALSE(startClassExam(c.admin, c.code, "ex", c.coordinator));  // closed: no new sitting
  auto progress = classProgress(instructor, c.code, "");
  REQUIRE(progress);
  for (const StudentClassProgress& s : progress->students) {
    CAPTURE(s.userName);
    CHECK(s.examsHandedIn == 1);
    CHECK(s.examScore == std::optional<double>(s.userName == c.eve ? 0.5 : 0.0));
  }
  CHECK(count(c.admin, "SELECT count(*) FROM class_audit WHERE class_code = '" + c.code +
                           "' AND action IN ('exam_open', 'exam_close') AND actor = '" + c.instructor + "'") == 2);
}

TEST_CASE("ClassExam_ServerGradesEqualTheKeys_ForRandomAnswers_AndTheDeadlineStopsGrading") {
  auto url = test::freshPostgresDatabase("the class exam test");
  if (!url) return;
  SecureClass c(*url);
  const std::uint64_t seed = test::freshSeed("ClassExam_ServerGradesEqualTheKeys");
  std::mt19937_64 random(seed);
  Database instructor = openAt(c.instructorUrl);
  const ClassExamOpening exam = toyExam("ex");
  REQUIRE(openClassExam(instructor, c.code, exam, std::nullopt));
  double expected = 0;
  for (const std::string& student : {c.eveUrl, c.samUrl}) {
    Database me = openAt(student);
    REQUIRE(startClassExam(me, c.code, "ex", std::nullopt));
    double score = 0;
    for (int position = 0; position < 4; ++position) {
      if (random() % 5 == 0) continue;  // left unanswered
      const ClassExamKey& key = exam.keys[std::size_t(position)];
      ClassExamAnswer a;
      bool right = false;
      if (exam.items[std::size_t(position)].kind == "identify") {
        a.choice = int(random() % 4);
        right = *a.choice == key.keyChoice;
      } else if (exam.items[std::size_t(position)].kind == "name") {
        const std::vector<std::string> said = {"stapes", "Stirrup", "incus", "stape"};
        a.text = said[random() % said.size()];
        right = *a.text == "stapes" || *a.text == "Stirrup";
      } else {  // half the clicks near the pixels that count, so that both grades occur
        const int x = random() % 2 ? int(random() % 40) : 4 + int(random() % 7);
        const int y = random() % 2 ? int(random() % 30) : 9 + int(random() % 4);
        a.pixel = std::array<int, 2>{x, y};
        right = (y == 10 && x >= 5 && x <= 9) || (y == 11 && x >= 6 && x <= 8);
      }
      REQUIRE(messageOf(answerClassExam(me, c.code, "ex", position, a, std::nullopt)) == "ok");
      score += right ? 1 : 0;
    }
    auto result = finishClassExam(me, c.code, "ex", std::nullopt);
    REQUIRE(result);
    CHECK(result->score == doctest::Approx(score / 4));
    expected += score / 4;
  }
  CHECK(count(c.admin, "SELECT round(sum(score) * 1000) FROM class_exam_sittings") == std::int64_t(std::llround(expected * 1000)));

  // Past the deadline an answer is refused and nothing is recorded.
  REQUIRE(openClassExam(instructor, c.code, toyExam("late"), std::nullopt));
  Database eve = openAt(c.eveUrl);
  REQUIRE(startClassExam(eve, c.code, "late", std::nullopt));
  REQUIRE(c.admin.exec("UPDATE class_exam_sittings SET deadline_at = deadline_at - 601 WHERE exam_id = 'late'"));
  const std::string before = examTables(c.admin);
  auto late = answerClassExam(eve, c.code, "late", 0, {2, std::nullopt, std::nullopt, 0}, std::nullopt);
  REQUIRE_FALSE(late);
  CHECK(late.error().message.find("time is up") != std::string::npos);
  CHECK(examTables(c.admin) == before);
  // A laptop's file holds no graded exams: an exam there is practice. (A SQLite file whatever
  // backend the suite runs on: a laptop never holds the class server's database.)
  test::TempDir dir;
  Database laptop = openAt((dir / "laptop.db").string());
  auto practice = startClassExam(laptop, c.code, "ex", std::nullopt);
  REQUIRE_FALSE(practice);
  CHECK(practice.error().message.find("practice") != std::string::npos);
}

TEST_CASE("ClassExam_PrerequisitesAreTheServers_AStudentStartsOnlyAfterFinishingThemThere") {
  auto url = test::freshPostgresDatabase("the class exam test");
  if (!url) return;
  SecureClass c(*url);
  Database instructor = openAt(c.instructorUrl);
  Database eve = openAt(c.eveUrl);
  ClassExamOpening exam = toyExam("after");
  exam.prerequisites = {"toy.ossicles"};
  REQUIRE(openClassExam(instructor, c.code, exam, std::nullopt));

  // Unfinished on the server: no sitting, whatever her laptop says; a forged lesson end is refused.
  auto locked = startClassExam(eve, c.code, "after", std::nullopt);
  REQUIRE_FALSE(locked);
  CHECK(locked.error().message.find("locked for " + c.eve + " until toy.ossicles is finished") != std::string::npos);
  const std::int64_t now = std::int64_t(std::time(nullptr));
  const auto record = [&](const std::string& kind, const std::string& question, std::optional<double> score,
                          const std::string& payload = "{}") {
    auto s = eve.prepare("SELECT at_record_event(?1, ?2, ?3, ?4, ?5, 'toy.ossicles', ?6, '', ?7, ?8, ?9)");
    REQUIRE(s);
    s->bind(1, newUuid()).bind(2, c.code).bind(3, c.eve).bind(4, kind).bind(5, now).bind(6, question);
    s->bind(7, score ? std::optional<std::int64_t>(1) : std::nullopt).bind(8, score).bind(9, payload);
    REQUIRE(*s->step());
    return s->text(0);
  };
  CHECK(record("lesson_finished", "", 1.0).rfind("refused: ", 0) == 0);
  CHECK_FALSE(startClassExam(eve, c.code, "after", std::nullopt));
  CHECK(count(c.admin, "SELECT count(*) FROM class_exam_sittings") == 0);
  // Play it through (the server checks each event), and the exam opens for her, not for sam.
  CHECK(record("lesson_started", "", std::nullopt) == "stored");
  // Each answer carries what was answered (the server grades it from its published keys).
  for (const auto& [q, answer] : std::vector<std::pair<std::string, std::string>>{
           {"toy.ossicles.name_stapes", R"({"answer": {"text": "stapes"}})"},
           {"toy.ossicles.identify_incus", R"({"answer": {"choice": 1}})"},
           {"toy.ossicles.locate_malleus", R"({"answer": {"pick": "malleus"}})"}})
    CHECK(record("answer", q, 1.0, answer) == "stored");
  CHECK(record("lesson_finished", "", 1.0) == "stored");
  auto sitting = startClassExam(eve, c.code, "after", std::nullopt);
  REQUIRE_MESSAGE(sitting, (sitting ? "" : sitting.error().message));
  Database sam = openAt(c.samUrl);
  CHECK_FALSE(startClassExam(sam, c.code, "after", std::nullopt));
  CHECK(count(c.admin, "SELECT count(*) FROM class_exam_sittings") == 1);
}
