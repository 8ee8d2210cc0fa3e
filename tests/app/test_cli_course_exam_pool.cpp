// `course validate` warns about an exam that asks more items than its pool holds (each structure
// once per kind it can be asked in; located only where a lesson of the course locates it), naming
// the exam and both counts; an exam whose count fits its pool gets no warning.
#include <doctest/doctest.h>

#include <fstream>
#include <set>
#include <string>

#include <nlohmann/json.hpp>

#include "test_support.h"

using namespace at;
namespace fs = std::filesystem;

TEST_CASE("CourseCli_Validate_WarnsAboutAnExamAskingMoreItemsThanItsPoolHolds") {
  if (!test::requireAppBinary("course validate")) return;
  test::TempDir dir;
  auto course = nlohmann::json::parse(test::readFile(test::sourceDir() / "data" / "courses" / "temporal_bone.json"));
  REQUIRE(course["exams"].size() == 1);
  auto& exam = course["exams"][0];
  // The pool, counted from the file: every kind but locate for each structure, and locate where a
  // lesson question locates it.
  std::set<std::string> located;
  for (const auto& lesson : course["lessons"])
    for (const auto& step : lesson["steps"])
      if (step["kind"] == "question" && step["question"]["kind"] == "locate")
        located.insert(step["question"]["target"].get<std::string>());
  std::size_t pool = 0;
  for (const auto& s : exam["structures"])
    for (const auto& k : exam["kinds"]) pool += k != "locate" || located.count(s.get<std::string>());
  const std::size_t most = exam["structures"].size() * exam["kinds"].size();
  REQUIRE(pool < most);  // else no count the reader accepts can exceed the pool
  const std::string id = exam["id"].get<std::string>();
  for (std::size_t count : {pool - 1, pool, pool + 1, most}) {
    exam["count"] = count;
    std::ofstream(dir / "exam.json") << course.dump();
    auto r = test::runApp("course validate '" + (dir / "exam.json").string() + "'");
    CAPTURE(count);
    CAPTURE(r.err);
    CHECK(r.exitCode == 0);
    CHECK(r.out.find("valid: course 'temporal_bone'") != std::string::npos);
    const std::string warning = "warning: exam '" + id + "' asks " + std::to_string(count) +
                                " items, but its pool holds only " + std::to_string(pool);
    if (count > pool) {
      CHECK(r.err.find(warning) != std::string::npos);
      CHECK(r.out.find("1 warning (see above)") != std::string::npos);
    } else {
      CHECK(r.err.find("warning") == std::string::npos);
    }
  }
}
