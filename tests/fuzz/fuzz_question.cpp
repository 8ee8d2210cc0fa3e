// One question object (as stored with answers and in course files) through parseQuestionJson.
#include "fuzz_support.h"
#include "lessons/course_json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto question = lessons::parseQuestionJson(text, "question.json");
  fuzz::checkResult(question, "question.json");
  if (!question) return 0;
  auto again = lessons::parseQuestionJson(lessons::questionToJson(*question), "again.json");
  fuzz::expect(bool(again), "a parsed question's JSON parses again");
  return 0;
}
