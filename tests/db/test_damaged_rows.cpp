// One damaged stored row (broken JSON in a question, an unknown step kind, synonyms of the wrong
// type) is left out with one line naming it; every other course and lesson still reads.
#include <doctest/doctest.h>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/course_store.h"
#include "db/sql_repositories.h"
#include "lessons/course_json.h"
#include "test_databases.h"
#include "test_support.h"
#include "toy_course.h"

using namespace at;
using namespace at::db;
using namespace at::lessons;

namespace {

Database openWithToyCourses(const test::TempDir& dir) {
  auto db = Database::open(test::freshDatabase(dir, "damaged.db"));
  REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
  REQUIRE(storeCourse(*db, test::toyCourse(), "memory"));
  Course other = test::toyCourse();
  other.id = "toy2";
  other.title = "Another toy";
  for (Lesson& l : other.lessons) {
    l.id = "toy2." + l.id.substr(4);
    for (std::string& p : l.prerequisites) p = "toy2." + p.substr(4);
    for (Step& s : l.steps)
      if (s.kind == StepKind::Question) s.question.id = "toy2." + s.question.id.substr(4);
  }
  REQUIRE(storeCourse(*db, other, "memory"));
  return std::move(*db);
}

}  // namespace

TEST_CASE("DamagedRow_BrokenQuestionJson_LessonLeftOutWithOneLineOthersStillWork") {
  test::TempDir dir;
  Database db = openWithToyCourses(dir);
  REQUIRE(db.exec("UPDATE questions SET json = '{\"kind\": \"name\", broken' WHERE id = 'toy.ossicles.name_stapes'"));
  SqlCurriculumRepository repo(db, test::toyBuiltin());

  auto all = repo.courses();
  REQUIRE_MESSAGE(all, (all ? "" : all.error().message));
  REQUIRE(all->size() == 2);
  for (const Course& c : *all) {
    CAPTURE(c.id);
    CHECK(c.lessons.size() == (c.id == "toy" ? 1u : 2u));
  }
  auto skipped = repo.takeSkipped();
  REQUIRE(skipped.size() == 1);
  CHECK(skipped[0].find("lesson 'toy.ossicles'") != std::string::npos);
  CHECK(skipped[0].find("left out") != std::string::npos);
  // Once per row: asking again lists the course without repeating the warning.
  REQUIRE(repo.course("toy"));
  CHECK(repo.takeSkipped().empty());
  // The other lessons play; the damaged one says what is wrong when asked for by name.
  CHECK(repo.lesson("toy.middle"));
  CHECK(repo.lesson("toy2.ossicles"));
  auto damaged = repo.lesson("toy.ossicles");
  REQUIRE_FALSE(damaged);
  CHECK(damaged.error().message.find("toy.ossicles") != std::string::npos);
}

TEST_CASE("DamagedRow_WrongTypesInStoredJson_CourseLeftOutInsteadOfThrowing") {
  test::TempDir dir;
  Database db = openWithToyCourses(dir);
  // Synonyms that are numbers once threw out of json::get (a crash of every command).
  REQUIRE(db.exec("UPDATE courses SET synonyms = '{\"stapes\": [1, 2]}' WHERE id = 'toy2'"));
  REQUIRE(db.exec("UPDATE questions SET json = '{\"kind\": 7, \"choices\": {}}' WHERE lesson_id = 'toy.middle'"));
  SqlCurriculumRepository repo(db, test::toyBuiltin());
  auto all = repo.courses();
  REQUIRE_MESSAGE(all, (all ? "" : all.error().message));
  REQUIRE(all->size() == 1);
  CHECK(all->front().id == "toy");
  CHECK(all->front().lessons.size() == 1);
  const auto skipped = repo.takeSkipped();
  REQUIRE(skipped.size() == 2);
  std::string joined;
  for (const auto& line : skipped) joined += line + "\n";
  CHECK(joined.find("course 'toy2'") != std::string::npos);
  CHECK(joined.find("lesson 'toy.middle'") != std::string::npos);
}
