// Courses (JSON, schema 1) through parseCourseJson; a course that parses must parse again from
// its own JSON.
#include "fuzz_support.h"
#include "lessons/course_json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto course = lessons::parseCourseJson(text, "course.json");
  fuzz::checkResult(course, "course.json");
  if (!course) return 0;
  auto again = lessons::parseCourseJson(lessons::courseToJson(*course), "again.json");
  fuzz::expect(bool(again), "a parsed course's JSON parses again");
  return 0;
}
