// A study export's long table (responses_long.csv, read back by `study merge` from export folders)
// through readResponsesLongCsv: a value or a one-line error naming the file; a table that reads
// must read again, unchanged, from what responsesLongCsv writes of its rows.
#include "fuzz_support.h"
#include "quiz/responses_long_reader.h"
#include "study_long_csv_study.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  static const quiz::StudyProtocol protocol = [] {
    auto p = quiz::parseStudyProtocol(fuzz::kLongCsvStudy, "study.json");
    fuzz::expect(p.has_value(), "the harness's study parses");
    return *p;
  }();
  const std::string source = "responses_long.csv";
  const auto rows = quiz::readResponsesLongCsv(std::string(reinterpret_cast<const char*>(data), size), source, protocol);
  fuzz::checkResult(rows, source);
  if (!rows) return 0;
  const std::string written = quiz::responsesLongCsv(*rows);
  const auto again = quiz::readResponsesLongCsv(written, source, protocol);
  fuzz::expect(again.has_value(), "what responsesLongCsv writes of read rows reads again");
  fuzz::expect(again->size() == rows->size() && quiz::responsesLongCsv(*again) == written,
               "the rows survive a second round trip unchanged");
  return 0;
}
