// A graded exam on a class server through the command line, as a class would run it: the
// instructor opens the shipped temporal-bone exam (items drawn and pictured on their machine), a
// student takes it from her laptop with her own login, the class's progress and xAPI show it.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "db/class_server.h"
#include "secure_class.h"
#include "test_support.h"

namespace fs = std::filesystem;
using namespace at;

namespace {

std::string after(const std::string& text, const std::string& marker) {
  const auto at = text.find(marker);
  if (at == std::string::npos) return "";
  const auto from = at + marker.size();
  return text.substr(from, text.find('\n', from) - from);
}

std::string accountUrl(const std::string& adminUrl, const std::string& code, const std::string& name, const char* role) {
  auto made = test::runApp("class account " + code + " " + name + " --role " + role + " --db '" + adminUrl + "'");
  CAPTURE(made.err);
  REQUIRE(made.exitCode == 0);
  const std::string password = after(made.out, "password (shown once, not stored; hand it to " + name + "): ");
  REQUIRE(password.size() == 24);
  return test::loginUrl(adminUrl, name, password);
}

}  // namespace

TEST_CASE("ClassExamCli_InstructorOpensStudentSitsOnTheServer_ProgressAndXapiShowTheServersGrade") {
  if (!test::requireAppBinary("the class exam CLI test")) return;
  auto url = test::freshPostgresDatabase("the class exam CLI test");
  if (!url) return;
  test::TempDir dir;
  const std::string lee = test::uniqueLogin("lee"), eve = test::uniqueLogin("eve");
  auto made = test::runApp("class create 'Temporal bone' --user " + lee + " --db '" + *url + "'");
  CAPTURE(made.err);
  REQUIRE(made.exitCode == 0);
  const std::string code = after(made.out, "code ").substr(0, 8);
  const std::string leeUrl = accountUrl(*url, code, lee, "coordinator");
  const std::string eveUrl = accountUrl(*url, code, eve, "student");
  const std::string instructorDb = (dir.path() / "lee.db").string(), laptop = (dir.path() / "eve.db").string();

  // A student cannot open it; the instructor can. The pictures are not left on the instructor's disk.
  const std::string open = "class open-exam " + code + " temporal_bone.practical --local-db '" + instructorDb +
                           "' --views '" + (dir.path() / "lee-views").string() + "' --db '";
  auto refused = test::runApp(open + eveUrl + "'");
  CHECK(refused.exitCode != 0);
  CHECK(refused.err.find("only its instructors and coordinators open exams") != std::string::npos);
  auto opened = test::runApp(open + leeUrl + "'");
  CAPTURE(opened.err);
  REQUIRE(opened.exitCode == 0);
  CHECK(opened.out.find("is open in class " + code + ": 12 items") != std::string::npos);
  CHECK(fs::is_empty(dir.path() / "lee-views"));

  // Eve joins from her laptop and answers the first two items: the first rightly (from the key the
  // test reads as the administrator; her login could not), the second wrongly.
  auto joined = test::runApp("class join " + code + " --server '" + eveUrl + "' --user " + eve + " --db '" + laptop + "'");
  CAPTURE(joined.err);
  REQUIRE(joined.exitCode == 0);
  db::Database admin = test::openAt(*url);
  // She answers every item up to the second locate item: the first item and the first locate item
  // rightly (from the keys the test reads as the administrator; her login could not), the others
  // wrongly — so a click on a pixel that counts and one that does not both reach the server.
  std::vector<int> locates;
  {
    auto s = admin.prepare("SELECT position FROM class_exam_items WHERE class_code = ?1 AND kind = 'locate' ORDER BY position");
    REQUIRE(s);
    s->bind(1, code);
    while (*s->step()) locates.push_back(s->integer(0));
  }
  // The class's draw decides how many locate items there are (none is possible: then the first two
  // items are answered; the pixel grading itself is tested in test_class_exams.cpp either way).
  if (locates.empty()) MESSAGE("class " << code << " drew no locate item: no click reaches the server here");
  const int answered = locates.size() >= 2 ? locates[1] + 1 : locates.size() == 1 ? std::max(locates[0], 1) + 1 : 2;
  const int rightCount = locates.empty() || locates[0] == 0 ? 1 : 2;
  const int clicks = int(std::min<std::size_t>(locates.size(), 2));
  std::string lines;
  for (int position = 0; position < answered; ++position) {
    auto s = admin.prepare("SELECT i.kind, k.key_choice, k.target, k.names FROM class_exam_items i JOIN class_exam_keys k"
                           " USING (class_code, exam_id, position) WHERE class_code = ?1 AND position = ?2");
    REQUIRE(s);
    s->bind(1, code).bind(2, position);
    REQUIRE(*s->step());
    const std::string kind = s->text(0);
    const bool right = position == 0 || (!locates.empty() && position == locates[0]);
    if (kind == "identify")
      lines += "{\"choice\": " + std::to_string(right ? s->integer(1) : (s->integer(1) + 1) % 4) + "}\n";
    else if (kind == "name")
      lines += nlohmann::json{{"text", right ? nlohmann::json::parse(s->text(3)).at(0).get<std::string>() : "nonsense"}}
                   .dump() + "\n";
    else {  // a pixel of the item's picture that counts, or one that does not
      auto pixel = admin.prepare(
          "SELECT gx.x, gy.y FROM class_exam_items i, generate_series(0, i.picture_width - 1) AS gx(x),"
          " generate_series(0, i.picture_height - 1) AS gy(y) WHERE i.class_code = ?1"
          " AND i.exam_id = 'temporal_bone.practical' AND i.position = ?2 AND ((?3 = 1) = EXISTS (SELECT 1"
          " FROM class_exam_locate_keys r WHERE r.class_code = i.class_code AND r.exam_id = i.exam_id"
          " AND r.position = i.position AND r.y = gy.y AND gx.x BETWEEN r.x_from AND r.x_to))"
          " ORDER BY gy.y, gx.x LIMIT 1");
      REQUIRE(pixel);
      pixel->bind(1, code).bind(2, position).bind(3, right ? 1 : 0);
      REQUIRE(*pixel->step());
      lines += nlohmann::json{{"pixel", {pixel->integer(0), pixel->integer(1)}}}.dump() + "\n";
    }
  }
  const fs::path answers = dir.path() / "answers.jsonl";
  std::ofstream(answers) << lines;
  const std::string sit = "exam temporal_bone.practical --user " + eve + " --new-user --db '" + laptop + "' --answers '" +
                          answers.string() + "' --views '" + (dir.path() / "eve-views").string() + "'";
  // Before she finished the exam's prerequisite lessons on the server, it does not start.
  auto locked = test::runApp(sit);
  CHECK(locked.exitCode != 0);
  CHECK(locked.err.find("locked for " + eve + " until inner_ear, facial_nerve, middle_ear is finished") != std::string::npos);
  CHECK(test::scalarCount(admin, "SELECT COUNT(*) FROM class_exam_sittings") == 0);
  // Their ends as the server stores them once her play-throughs are synced (at_record_event checks
  // each event; tests/db/test_class_exams.cpp plays one through).
  for (const char* lesson : {"inner_ear", "facial_nerve", "middle_ear"})
    REQUIRE(admin.exec("INSERT INTO class_events (uuid, class_code, user_name, kind, occurred_at, lesson_id, score,"
                       " received_at) VALUES (gen_random_uuid()::text, '" + code + "', '" + eve + "', 'lesson_finished',"
                       " 1700000000, '" + lesson + "', 1, 1700000000)"));
  auto sat = test::runApp(sit);
  CAPTURE(sat.out);
  CAPTURE(sat.err);
  REQUIRE(sat.exitCode == 0);
  CHECK(sat.out.find("Graded exam of class " + code) != std::string::npos);
  char results[120];
  std::snprintf(results, sizeof results, "Handed in. Results from the class server: %d of 12 items right, score %.2f",
                rightCount, rightCount / 12.0);
  CHECK(sat.out.find(results) != std::string::npos);
  CHECK(test::scalarCount(admin, "SELECT COUNT(*) FROM class_exam_answers WHERE answer LIKE '{\"pixel\"%'") == clicks);
  // Her laptop's file holds none of the exam's items or keys.
  db::Database local = test::openAt(laptop);
  CHECK(test::scalarCount(local, "SELECT COUNT(*) FROM exam_items") == 0);
  auto again = test::runApp(sit);
  CHECK(again.out.find("You handed this exam in already") != std::string::npos);

  auto csv = test::runApp("class progress " + code + " --csv --db '" + leeUrl + "'");
  CAPTURE(csv.err);
  REQUIRE(csv.exitCode == 0);
  CAPTURE(csv.out);
  // Her line ends with the exam columns (one handed in, the server's score), then no answer waiting
  // for its key and none kept as practice.
  char examColumns[40];
  std::snprintf(examColumns, sizeof examColumns, ",1,%.3f,0,0", rightCount / 12.0);
  const std::string eveLine = after(csv.out, "\n" + eve + ",");
  CHECK(eveLine.ends_with(examColumns));

  // Analytics on the server counts the same exam: her score in the students table, one finished
  // attempt in the exams table.
  auto analytics = test::runApp("analytics temporal_bone --group " + code + " --csv --db '" + *url + "'");
  CAPTURE(analytics.err);
  REQUIRE(analytics.exitCode == 0);
  CAPTURE(analytics.out);
  const std::string scoreLine = "\nstudents," + eve + "," + code + ",exam_score,";
  const auto scoreAt = analytics.out.find(scoreLine);
  REQUIRE(scoreAt != std::string::npos);
  CHECK(std::stod(analytics.out.substr(scoreAt + scoreLine.size())) == doctest::Approx(rightCount / 12.0).epsilon(1e-3));
  bool finishedOnce = false;
  std::istringstream analyticsLines(analytics.out);
  for (std::string line; std::getline(analyticsLines, line);)
    finishedOnce = finishedOnce || (line.rfind("exams,temporal_bone.practical,", 0) == 0 && line.ends_with(",finished,1"));
  CHECK(finishedOnce);

  const fs::path xapi = dir.path() / "class.json";
  auto exported = test::runApp("xapi --class " + code + " --out '" + xapi.string() + "' --db '" + leeUrl + "'");
  CAPTURE(exported.err);
  REQUIRE(exported.exitCode == 0);
  const auto statements = nlohmann::json::parse(test::readFile(xapi));
  CAPTURE(statements.dump());
  std::size_t examStatements = 0;
  for (const auto& st : statements)
    examStatements += st.dump().find("temporal_bone.practical") != std::string::npos ? 1 : 0;
  CHECK(examStatements == std::size_t(answered + 2));  // attempted, each answer, completed
  CHECK(statements.back().at("result").at("score").at("scaled").get<double>() == doctest::Approx(rightCount / 12.0));
  CHECK(statements.back().at("result").at("success") == false);
  if (std::system("command -v node > /dev/null 2>&1") == 0) {
    const std::string validate = "bash '" + (test::sourceDir() / "scripts/xapi-validator.sh").string() + "' validate '" +
                                 xapi.string() + "' > /dev/null 2>&1";
    CHECK(std::system(validate.c_str()) == 0);
  }
}
