// Study protocols (JSON) through parseStudyProtocol; a protocol that parses must come back equal
// from its own serialisation (the parser's documented lossless round trip).
#include "fuzz_support.h"
#include "quiz/study_protocol.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string text(reinterpret_cast<const char*>(data), size);
  auto protocol = quiz::parseStudyProtocol(text, "study.json");
  fuzz::checkResult(protocol, "study.json");
  if (!protocol) return 0;
  auto again = quiz::parseStudyProtocol(quiz::serialiseStudyProtocol(*protocol), "again.json");
  fuzz::expect(again && *again == *protocol, "a protocol survives its own serialisation");
  return 0;
}
