// Answers: each line of the input is one JSON answer as `play --answers FILE.jsonl` reads them.
#include "fuzz_support.h"
#include "quiz/answer_json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    auto answer = quiz::answerFromJson(std::string(text.substr(start, end - start)));
    fuzz::checkResult(answer, "");
    if (answer) fuzz::expect(bool(quiz::answerFromJson(quiz::answerToJson(*answer))), "an answer's JSON parses again");
    start = end + 1;
  }
  return 0;
}
