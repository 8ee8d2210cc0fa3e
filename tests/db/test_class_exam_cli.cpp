// A graded exam on a class server through the command line, as a class would run it: the
// instructor opens the shipped temporal-bone exam (items drawn and pictured on their machine), a
// student takes it from her laptop with her own login, the class's progress and xAPI show it.
#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
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
  std::string lines;
  for (int position = 0; position < 2; ++position) {
    auto s = admin.prepare("SELECT i.kind, k.key_choice, k.target, k.names FROM class_exam_items i JOIN class_exam_keys k"
                           " USING (class_code, exam_id, position) WHERE class_code = ?1 AND position = ?2");
    REQUIRE(s);
    s->bind(1, code).bind(2, position);
    REQUIRE(*s->step());
    const std::string kind = s->text(0);
    const bool right = position == 0;
    if (kind == "identify")
      lines += "{\"choice\": " + std::to_string(right ? s->integer(1) : (s->integer(1) + 1) % 4) + "}\n";
    else if (kind == "name")
      lines += nlohmann::json{{"text", right ? nlohmann::json::parse(s->text(3)).at(0).get<std::string>() : "nonsense"}}
                   .dump() + "\n";
    else
      lines += nlohmann::json{{"pick", right ? s->text(2) : ""}}.dump() + "\n";
  }
  const fs::path answers = dir.path() / "answers.jsonl";
  std::ofstream(answers) << lines;
  const std::string sit = "exam temporal_bone.practical --user " + eve + " --new-user --db '" + laptop + "' --answers '" +
                          answers.string() + "' --views '" + (dir.path() / "eve-views").string() + "'";
  auto sat = test::runApp(sit);
  CAPTURE(sat.out);
  CAPTURE(sat.err);
  REQUIRE(sat.exitCode == 0);
  CHECK(sat.out.find("Graded exam of class " + code) != std::string::npos);
  CHECK(sat.out.find("Handed in. Results from the class server: 1 of 12 items right, score 0.08") != std::string::npos);
  // Her laptop's file holds none of the exam's items or keys.
  db::Database local = test::openAt(laptop);
  CHECK(test::scalarCount(local, "SELECT COUNT(*) FROM exam_items") == 0);
  auto again = test::runApp(sit);
  CHECK(again.out.find("You handed this exam in already") != std::string::npos);

  auto csv = test::runApp("class progress " + code + " --csv --db '" + leeUrl + "'");
  CAPTURE(csv.err);
  REQUIRE(csv.exitCode == 0);
  CHECK(csv.out.find("\n" + eve + ",0,0,0,0,0,,,1,0.083\n") != std::string::npos);

  const fs::path xapi = dir.path() / "class.json";
  auto exported = test::runApp("xapi --class " + code + " --out '" + xapi.string() + "' --db '" + leeUrl + "'");
  CAPTURE(exported.err);
  REQUIRE(exported.exitCode == 0);
  const auto statements = nlohmann::json::parse(test::readFile(xapi));
  REQUIRE(statements.size() == 4);  // attempted, two answers, completed
  CHECK(statements.back().at("result").at("score").at("scaled").get<double>() == doctest::Approx(1.0 / 12));
  CHECK(statements.back().at("result").at("success") == false);
  if (std::system("command -v node > /dev/null 2>&1") == 0) {
    const std::string validate = "bash '" + (test::sourceDir() / "scripts/xapi-validator.sh").string() + "' validate '" +
                                 xapi.string() + "' > /dev/null 2>&1";
    CHECK(std::system(validate.c_str()) == 0);
  }
}
