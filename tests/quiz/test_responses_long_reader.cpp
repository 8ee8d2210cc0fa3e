#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "quiz/responses_long_reader.h"
#include "quiz/study_protocol.h"
#include "quiz/study_report.h"
#include "small_study.h"

using namespace at::quiz;

namespace {

// One participant's two structures × two items, with the awkward values an export can hold.
std::vector<StudyResponseRow> bundleRows() {
  std::vector<StudyResponseRow> rows;
  const char* structures[] = {"stapes", "cochlea"};
  const char* items[] = {"shape", "context"};
  for (int s = 0; s < 2; ++s)
    for (int i = 0; i < 2; ++i) {
      StudyResponseRow r;
      r.participantId = "P-1";
      r.group = "medical";
      r.session = s + 1;
      r.structure = structures[s];
      r.item = items[i];
      r.aCondition = s == 0 ? "wdt" : "bare";
      r.ratingAb = 2 + i;
      r.rating = s == 0 ? r.ratingAb : 6 - r.ratingAb;
      r.presentationOrder = s + 1;
      r.presetA = r.structure + (s == 0 ? "_wdt" : "_bare");
      r.presetB = r.structure + (s == 0 ? "_bare" : "_wdt");
      r.t = 0.5;
      r.alpha = 1.25;
      r.beta = -0.125;
      r.viewingMeasured = s == 0;  // the second structure was shown as files: times not known
      r.viewMsA = s == 0 ? 3000 : 0;
      r.viewMsB = s == 0 ? 2500 : 0;
      r.toggles = s == 0 ? 3 : 0;
      r.responseMs = 812;
      r.timestampUtc = "2026-11-22T05:01:0" + std::to_string(2 * s + i) + "Z";
      r.appVersion = "0.9.0";
      r.comment = s == 0 ? "=looks \"sharp\", clear\nsecond line" : "";
      r.participantComplete = false;
      if (s == 0) {
        r.qualityLevel = 2;
        r.qualityFullLevel = 2;
        r.qualityScale = 0.5;
        r.settleMs = 1690;
      }
      rows.push_back(r);
    }
  return rows;
}

// The export's text with one cell of data row `row` (1-based among data rows) replaced.
std::string withCell(std::size_t row, const std::string& column, const std::string& value) {
  auto records = parseCsv(responsesLongCsv(bundleRows()));
  const auto& names = responsesLongColumnNames();
  const std::size_t c = std::size_t(std::find(names.begin(), names.end(), column) - names.begin());
  REQUIRE(c < names.size());
  records[row][c] = value;
  std::string text;
  for (const auto& record : records) {
    std::vector<std::string> cells;
    for (const auto& cell : record) cells.push_back(csvQuoted(cell));
    text += csvRecord(cells);
  }
  return text;
}

std::string errorOf(const std::string& text) {
  auto rows = readResponsesLongCsv(text, "lab2/responses_long.csv", at::test::smallStudyProtocol());
  REQUIRE_FALSE(rows.has_value());
  CHECK(rows.error().message.find('\n') == std::string::npos);
  CHECK(rows.error().message.rfind("lab2/responses_long.csv: ", 0) == 0);
  return rows.error().message;
}

}  // namespace

TEST_CASE("ResponsesLongReader_ReadsTheExportBack_SameRowsSameText") {
  const auto rows = bundleRows();
  const std::string text = responsesLongCsv(rows);
  auto read = readResponsesLongCsv(text, "responses_long.csv", at::test::smallStudyProtocol());
  REQUIRE_MESSAGE(read.has_value(), read.error().message);
  REQUIRE(read->size() == rows.size());
  CHECK(responsesLongCsv(*read) == text);  // every column survives, the formula guard is undone
  CHECK((*read)[0].comment == rows[0].comment);
  CHECK((*read)[0].qualityScale == 0.5);
  CHECK_FALSE((*read)[2].viewingMeasured);
  CHECK_FALSE((*read)[2].qualityLevel.has_value());
  CHECK((*read)[3].session == 2);

  // LF line ends and a byte order mark (a spreadsheet saved it again) read the same.
  std::string lf;
  for (char c : text)
    if (c != '\r') lf += c;
  auto relaxed = readResponsesLongCsv("\xEF\xBB\xBF" + lf, "responses_long.csv", at::test::smallStudyProtocol());
  REQUIRE_MESSAGE(relaxed.has_value(), relaxed.error().message);
  CHECK(responsesLongCsv(*relaxed) == text);

  // An export written before the quality columns: 22 columns, quality unknown.
  auto records = parseCsv(text);
  std::string older;
  for (auto& record : records) {
    record.resize(22);
    std::vector<std::string> cells;
    for (const auto& cell : record) cells.push_back(csvQuoted(cell));
    older += csvRecord(cells);
  }
  auto old = readResponsesLongCsv(older, "responses_long.csv", at::test::smallStudyProtocol());
  REQUIRE_MESSAGE(old.has_value(), old.error().message);
  CHECK_FALSE((*old)[0].qualityLevel.has_value());
  CHECK((*old)[0].rating == rows[0].rating);

  // A header alone: no rows.
  auto empty = readResponsesLongCsv(responsesLongCsv({}), "responses_long.csv", at::test::smallStudyProtocol());
  REQUIRE(empty.has_value());
  CHECK(empty->empty());
}

TEST_CASE("ResponsesLongReader_BadInput_OneLineErrorNamingFileRowAndColumn") {
  CHECK(errorOf("").find("empty file") != std::string::npos);
  CHECK(errorOf("participant_id,group\r\n").find("row 1 has 2 columns") != std::string::npos);
  std::string header = responsesLongCsv({});
  header.replace(header.find("rating_ab"), 9, "rating_xy");
  CHECK(errorOf(header).find("row 1, column 6 is 'rating_xy', expected 'rating_ab'") != std::string::npos);

  CHECK(errorOf(withCell(3, "rating_ab", "6")).find("row 4, column 'rating_ab': 6 is outside 1–5") != std::string::npos);
  CHECK(errorOf(withCell(1, "rating", "4")).find("row 2, column 'rating': 4 does not unblind rating_ab 2") !=
        std::string::npos);
  CHECK(errorOf(withCell(2, "structure", "femur")).find("row 3, column 'structure': 'femur' is not a structure") !=
        std::string::npos);
  CHECK(errorOf(withCell(2, "item", "beauty")).find("column 'item': 'beauty' is not an item") != std::string::npos);
  CHECK(errorOf(withCell(2, "group", "nurses")).find("column 'group': 'nurses' is not a group") != std::string::npos);
  CHECK(errorOf(withCell(1, "a_condition", "x")).find("column 'a_condition'") != std::string::npos);
  CHECK(errorOf(withCell(1, "participant_id", "P 1")).find("column 'participant_id': participant id 'P 1'") !=
        std::string::npos);
  CHECK(errorOf(withCell(1, "t", "nan")).find("column 't': 'nan' is not a finite number") != std::string::npos);
  CHECK(errorOf(withCell(1, "t", "1e999")).find("column 't'") != std::string::npos);
  CHECK(errorOf(withCell(1, "response_ms", "-5")).find("column 'response_ms': '-5' is negative") != std::string::npos);
  CHECK(errorOf(withCell(1, "response_ms", "5e62")).find("column 'response_ms': '5e62' is beyond 31536000000") !=
        std::string::npos);  // no time comes near a year
  CHECK(errorOf(withCell(1, "alpha", "-2e6")).find("column 'alpha': '-2e6' is beyond 1000000") != std::string::npos);
  CHECK(errorOf(withCell(1, "session", "two")).find("column 'session': 'two' is not a whole number") !=
        std::string::npos);
  CHECK(errorOf(withCell(1, "presentation_order", "3")).find("column 'presentation_order': 3 is outside 1–2") !=
        std::string::npos);
  CHECK(errorOf(withCell(1, "timestamp", "yesterday")).find("column 'timestamp': 'yesterday' is not an ISO 8601") !=
        std::string::npos);
  CHECK(errorOf(withCell(1, "toggles", "")).find("column 'toggles': is blank while the other viewing columns") !=
        std::string::npos);
  CHECK(errorOf(withCell(1, "participant_complete", "yes")).find("column 'participant_complete'") != std::string::npos);
  // Rows that disagree about one participant or one trial.
  CHECK(errorOf(withCell(4, "group", "non-medical")).find("row 5, column 'group': participant 'P-1' is in group "
                                                           "'medical' on row 2") != std::string::npos);
  CHECK(errorOf(withCell(2, "comment", "other")).find("row 3, column 'comment': differs from the comment on row 2") !=
        std::string::npos);
  CHECK(errorOf(withCell(2, "item", "shape")).find("row 3, column 'item': 'shape' of 'stapes' for participant "
                                                   "'P-1' is rated twice (also on row 2)") != std::string::npos);
  CHECK(errorOf(withCell(3, "presentation_order", "1")).find("row 4, column 'structure': differs") != std::string::npos);

  // Broken CSV.
  const std::string good = responsesLongCsv(bundleRows());
  CHECK(errorOf(good + "\"P-2,medical").find("a quoted cell is not closed") != std::string::npos);
  CHECK(errorOf(good + "P\"2,medical\r\n").find("a quote inside a cell") != std::string::npos);
  CHECK(errorOf(good + "\"P-2\"x,medical\r\n").find("text after the closing quote") != std::string::npos);
  CHECK(errorOf(good + "P-2\rmedical").find("carriage return") != std::string::npos);
  CHECK(errorOf(good + "P-2,medical\r\n").find("row 6 has 2 cells, the header 26") != std::string::npos);
  CHECK(errorOf(good + "\r\n").find("row 6 has 1 cells") != std::string::npos);
  // Control characters from the file are quoted printably.
  CHECK(errorOf(withCell(1, "structure", "\x1b[31mred")).find("\\x1b[31mred") != std::string::npos);
}

TEST_CASE("ResponsesLongReader_HugeNumbers_WrittenWholeAndRefusedOnReading") {
  // csvNumber once cut numbers of more than 63 characters (the fuzz harness's first finding); every
  // double is now written whole, and the reader refuses times beyond a year.
  const double huge = 5.555555555555555e70;
  const std::string text = csvNumber(huge, 0);
  CHECK(text.size() == 71);
  CHECK(std::stod(text) == huge);
  CHECK(csvNumber(-1.7976931348623157e308, 3).size() == 310);
  auto rows = bundleRows();
  rows[0].responseMs = huge;
  auto read = readResponsesLongCsv(responsesLongCsv(rows), "responses_long.csv", at::test::smallStudyProtocol());
  REQUIRE_FALSE(read.has_value());
  CHECK(read.error().message.find("row 2, column 'response_ms'") != std::string::npos);
}
