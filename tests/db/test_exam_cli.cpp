// `anatomy-tutor exam` through the real binary: items drawn and stored, names and grades hidden
// until the end, every answer saved as given, the clock, results and score in the database.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "test_databases.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/phantom.h"

namespace fs = std::filesystem;
using namespace at;

namespace {

std::int64_t scalar(const std::string& dbPath, const std::string& sql) {
  auto db = db::Database::open(dbPath);
  REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
  auto s = db->prepare(sql);
  REQUIRE_MESSAGE(s, (s ? "" : s.error().message));
  REQUIRE(*s->step());
  return s->int64(0);
}

struct Item {
  std::string kind, structure;
};

std::vector<Item> itemsOfOpenAttempt(const std::string& dbPath) {
  auto db = db::Database::open(dbPath);
  REQUIRE(db);
  auto s = db->prepare(
      "SELECT kind, structure FROM exam_items WHERE attempt_id = (SELECT max(id) FROM exam_attempts) ORDER BY position");
  REQUIRE(s);
  std::vector<Item> items;
  while (*s->step()) items.push_back({s->text(0), s->text(1)});
  return items;
}

// A point inside a structure of the phantom at 128³ (where the terminal reads points in mm).
std::string pointInside(const Dataset& phantom, const std::string& structureId) {
  const Structure* s = phantom.findStructure(structureId);
  REQUIRE(s);
  const Dims& d = phantom.labels.dims();
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i)
        if (phantom.labels.at(i, j, k) == s->label) {
          const Vec3 p = phantom.labels.geometry.indexToPatient({double(i), double(j), double(k)});
          return "[" + std::to_string(p[0]) + ", " + std::to_string(p[1]) + ", " + std::to_string(p[2]) + "]";
        }
  FAIL("no voxel of " << structureId);
  return "";
}

}  // namespace

TEST_CASE("exam hides names and grades until the end, saves every answer, scores and passes; the clock ends it") {
  if (!test::requireAppBinary("the exam command")) return;
  const auto structures = phantomStructures();
  test::TempDir dir("exam-cli");
  fs::create_directories(dir / "data" / "courses");
  const std::string a = structures[0].id, b = structures[1].id;
  {
    std::ofstream course(dir / "data" / "courses" / "ex.json");
    course << R"({"schema": 1, "id": "ex", "title": "Exam course", "dataset": "phantom", "version": 1,
      "lessons": [{"id": "ex.look", "title": "Look", "steps": [{"kind": "show", "structure": ")" << a
           << R"(", "preset": ")" << a << R"(_wdt", "view": "superior", "title": "T", "text": "X"},
        {"kind": "question", "structure": ")" << b << R"(", "preset": ")" << b << R"(_wdt", "view": "superior",
         "question": {"id": "ex.look.locate_a", "kind": "locate", "prompt": "Click it.", "target": ")" << a << R"("}},
        {"kind": "question", "structure": ")" << a << R"(", "preset": ")" << a << R"(_wdt", "view": "superior",
         "question": {"id": "ex.look.locate_b", "kind": "locate", "prompt": "Click it.", "target": ")" << b << R"("}}]}],
      "exams": [{"id": "ex.exam", "title": "Quick exam", "structures": [")" << a << "\", \"" << b
           << R"("], "kinds": ["name", "locate"], "count": 4, "time_limit_s": 600, "pass_score": 0.7,
                 "locate_views": ["3d"]}]})";
  }
  const std::string db = test::freshDatabase(dir, "t.db");
  ::setenv("AT_DATA_DIR", (dir / "data").c_str(), 1);
  const auto exam = [&](const std::string& args, const std::string& input = "") {
    return test::runApp("exam ex.exam --user kim --new-user --no-views --db '" + db + "' " + args, input);
  };

  // Start and leave at once: the items are drawn and stored, the attempt stays open.
  auto first = exam("", "quit\n");
  INFO(first.out << first.err);
  REQUIRE(first.exitCode == 0);
  CHECK(first.out.find("4 items, 10:00, pass mark 70%. Labels are hidden and no answer is marked until you finish.") !=
        std::string::npos);
  CHECK(first.out.find("left the exam") != std::string::npos);
  const auto items = itemsOfOpenAttempt(db);
  REQUIRE(items.size() == 4);
  // Each structure once before either repeats, each item once (the course locates both
  // structures, so the four items are both kinds of both); a name item never shows its name.
  CHECK(items[0].structure != items[1].structure);
  std::set<std::string> distinct;
  for (const Item& item : items) distinct.insert(item.kind + " " + item.structure);
  CHECK(distinct.size() == 4);
  CHECK(first.out.find("[1/4] ") != std::string::npos);
  CHECK(first.out.find(items[0].kind == "name" ? " left — Name the marked structure." : " left — Locate the ") !=
        std::string::npos);
  if (items[0].kind == "name")
    for (const Structure& s : structures) CHECK(first.out.find(s.displayName) == std::string::npos);

  // Answer: right, right, wrong, right (names typed as display names, locate as points in mm).
  auto phantom = openBuiltinDataset("phantom:128");
  REQUIRE(phantom);
  const auto answerFor = [&](const Item& item, bool right) {
    const std::string other = item.structure == a ? b : a;
    const std::string id = right ? item.structure : other;
    if (item.kind == "name") return "{\"text\": \"" + phantom->findStructure(id)->displayName + "\"}";
    return "{\"point_mm\": " + pointInside(*phantom, id) + "}";
  };
  {
    std::ofstream answers(dir / "answers.jsonl");
    answers << answerFor(items[0], true) << "\n" << answerFor(items[1], true) << "\n"
            << answerFor(items[2], false) << "\n" << answerFor(items[3], true) << "\n";
  }
  auto second = exam("--answers '" + (dir / "answers.jsonl").string() + "'");
  INFO(second.out << second.err);
  REQUIRE(second.exitCode == 0);
  CHECK(second.out.find("Continuing: 0 of 4 answered") != std::string::npos);
  const auto handedIn = second.out.find("Handed in.");
  REQUIRE(handedIn != std::string::npos);
  // No grade before the end.
  CHECK(second.out.substr(0, handedIn).find("✓") == std::string::npos);
  CHECK(second.out.substr(0, handedIn).find("✗") == std::string::npos);
  CHECK(second.out.find("(saved)") < handedIn);
  CHECK(second.out.find("Results: 3 of 4 items right, score 0.75 — passed (pass mark 0.70)") != std::string::npos);
  CHECK(second.out.find(" 3. ") != std::string::npos);
  {  // the review: every item with the answer given and the right one
    const std::string review = second.out.substr(handedIn);
    std::size_t lines = 0;
    for (auto at = review.find("      you: "); at != std::string::npos; at = review.find("      you: ", at + 1)) ++lines;
    CHECK(lines == 4);
    CHECK(review.find("   answer: ") != std::string::npos);
  }
  CHECK(scalar(db, "SELECT count(*) FROM exam_attempts WHERE finished_at IS NOT NULL AND score = 0.75 AND passed = 1") == 1);
  CHECK(scalar(db, "SELECT count(*) FROM exam_items WHERE answer IS NOT NULL") == 4);
  CHECK(scalar(db, "SELECT sum(correct) FROM exam_items") == 3);
  CHECK(scalar(db, "SELECT count(*) FROM review_log WHERE source = 'exam'") == 4);
  // The student's own progress lists the exam with its score.
  auto progress = test::runApp("progress --user kim --db '" + db + "'");
  INFO(progress.out);
  CHECK(progress.out.find("score 0.75, passed (1 attempt)") != std::string::npos);

  // A new attempt whose time runs out: answers are refused and the attempt ends with what it had.
  auto third = exam("", "quit\n");
  REQUIRE(third.exitCode == 0);
  REQUIRE(scalar(db, "SELECT count(*) FROM exam_attempts") == 2);
  {
    auto database = db::Database::open(db);
    REQUIRE(database);
    REQUIRE(database->exec("UPDATE exam_attempts SET started_at = started_at - 900, deadline_at = deadline_at - 900"
                           " WHERE finished_at IS NULL"));
  }
  auto late = exam("--answers '" + (dir / "answers.jsonl").string() + "'");
  INFO(late.out << late.err);
  CHECK(late.exitCode == 0);
  CHECK(late.out.find("Time is up.") != std::string::npos);
  CHECK(late.out.find("Results: 0 of 4 items right, score 0.00 — not passed") != std::string::npos);
  CHECK(scalar(db, "SELECT count(*) FROM exam_items WHERE answer IS NOT NULL") == 4);  // only the first attempt's
  CHECK(scalar(db, "SELECT count(*) FROM exam_attempts WHERE finished_at IS NOT NULL") == 2);

  // Bad input: an unknown exam; a malformed answers line names its line and keeps earlier answers.
  auto unknown = test::runApp("exam nope --user kim --no-views --db '" + db + "'");
  CHECK(unknown.exitCode != 0);
  CHECK(unknown.err.find("unknown exam 'nope'") != std::string::npos);
  REQUIRE(exam("", "quit\n").exitCode == 0);
  const auto fourth = itemsOfOpenAttempt(db);
  REQUIRE(fourth.size() == 4);
  {
    std::ofstream broken(dir / "broken.jsonl");
    broken << answerFor(fourth[0], true) << "\n{\"text\": \n";
  }
  auto bad = exam("--answers '" + (dir / "broken.jsonl").string() + "'");
  CHECK(bad.exitCode != 0);
  CHECK(bad.err.find("broken.jsonl:2: ") != std::string::npos);
  CHECK(scalar(db, "SELECT count(*) FROM exam_items WHERE answer IS NOT NULL AND attempt_id = (SELECT max(id) FROM exam_attempts)") == 1);
  ::unsetenv("AT_DATA_DIR");
}
