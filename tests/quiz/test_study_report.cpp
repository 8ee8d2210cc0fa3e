#include <doctest/doctest.h>

#include <algorithm>

#include <cmath>
#include <map>

#include "quiz/study_design.h"
#include "quiz/study_protocol.h"
#include "quiz/study_report.h"
#include "small_study.h"
#include "test_support.h"

using namespace at::quiz;

namespace {

StudyProtocol smallProtocol() { return at::test::smallStudyProtocol(); }

StudyResponseRow row(const std::string& participant, const std::string& group, const std::string& structure,
                     const std::string& item, int rating) {
  StudyResponseRow r;
  r.participantId = participant;
  r.group = group;
  r.structure = structure;
  r.item = item;
  r.rating = rating;
  r.ratingAb = rating;
  r.aCondition = "wdt";
  r.timestampUtc = "2026-11-22T05:00:00Z";
  r.appVersion = "0.1.0";
  return r;
}

}  // namespace

TEST_CASE("StudyProtocol_ShippedPaperSurvey_ParsesAndRoundTrips") {
  auto p = loadStudyProtocol((at::test::sourceDir() / "data/studies/paper_survey.json").string());
  REQUIRE_MESSAGE(p.has_value(), p.error().message);
  CHECK(p->structures.size() == 13);
  CHECK(p->items.size() == 4);
  CHECK(p->groups == std::vector<std::string>{"non-medical", "medical"});
  CHECK(p->presetFor("cochlea", 0) == "cochlea_wdt");
  CHECK(p->presetFor("cochlea", 1) == "cochlea_bare");
  auto again = parseStudyProtocol(serialiseStudyProtocol(*p), "round-trip");
  REQUIRE(again.has_value());
  CHECK(*again == *p);
}

TEST_CASE("StudyProtocol_InvalidFields_AreRejectedByName") {
  const std::string base = R"("id": "s", "dataset": "phantom", "structures": ["cochlea"],
    "conditions": [{"id": "wdt"}, {"id": "bare"}], "items": [{"id": "shape", "wording": "Shape?"}],
    "groups": ["g"])";
  struct Case { std::string json; std::string mentions; };
  const Case cases[] = {
      {"{" + base + R"(, "colour": 1})", "'colour' is not a known field"},
      {"{" + base + R"(, "seed": "x"})", "'seed' must be an integer"},
      {"{" + base + R"(, "t": 2})", "'t' must lie in 0..1"},
      {"{" + base + R"(, "scale": {"min": 1, "max": 4}})", "'scale'"},
      {R"({"id": "s", "dataset": "phantom", "structures": ["cochlea"], "conditions": [{"id": "wdt"}],
          "items": [{"id": "shape", "wording": "Shape?"}], "groups": ["g"]})", "'conditions'"},
      {R"({"id": "s", "dataset": "phantom", "structures": ["cochlea", "cochlea"], "conditions": [{"id": "wdt"}, {"id": "bare"}],
          "items": [{"id": "shape", "wording": "Shape?"}], "groups": ["g"]})", "'structures[1]' repeats"},
      {R"({"id": "s", "dataset": "phantom", "structures": ["cochlea"], "conditions": [{"id": "wdt"}, {"id": "bare"}],
          "items": [{"id": "shape", "wording": 3}], "groups": ["g"]})", "'items[0].wording' must be a string"},
      {"{not json", "not valid JSON"},
      // A number beyond a double is reported with its line and field, like the checks above.
      {"{" + base + ",\n \"t\": 1e309}", "bad.json: line 4, column 12, field 't': number 1e309 is out of range"},
      // Scale ends far apart once overflowed int arithmetic (max − min).
      {"{" + base + R"(, "scale": {"min": -2147483648, "max": 2147483647}})", "'scale.min' must lie in -1000..1000"},
  };
  for (const Case& c : cases) {
    auto p = parseStudyProtocol(c.json, "bad.json");
    REQUIRE_FALSE(p.has_value());
    CAPTURE(p.error().message);
    CHECK(p.error().message.find(c.mentions) != std::string::npos);
    CHECK(p.error().message.rfind("bad.json", 0) == 0);
  }
}

TEST_CASE("UnblindRating_ParticipantWhoAlwaysPicksWdt_GetsOneWhateverA") {
  const StudyScale scale;
  for (std::size_t participant = 0; participant < 8; ++participant) {
    for (const TrialPlan& t : planParticipant(13, participant, 3)) {
      // The participant always prefers the WDT view: rating "prefer A" when WDT is A, else "prefer B".
      const int shown = t.aIsFirstCondition ? 1 : 5;
      CHECK(unblindRating(shown, t.aIsFirstCondition, scale) == 1);
    }
  }
  CHECK(unblindRating(2, false, scale) == 4);
  CHECK(unblindRating(3, false, scale) == 3);
}

TEST_CASE("CsvCell_HostileText_RoundTripsAndIsNeutralised") {
  const std::string hostile[] = {"=HYPERLINK(\"http://x\")", "+1+2", "-3", "@SUM(A1)", "plain, with comma",
                                 "quote \" inside", "two\nlines", "crlf\r\nend", "Ünïcødé — 耳蜗", ""};
  std::vector<std::string> cells;
  for (const auto& h : hostile) cells.push_back(csvCell(h));
  const auto parsed = parseCsv(csvRecord(cells));
  REQUIRE(parsed.size() == 1);
  REQUIRE(parsed[0].size() == cells.size());
  for (std::size_t i = 0; i < cells.size(); ++i) {
    std::string expected = hostile[i];
    if (!expected.empty() && std::string("=+-@").find(expected[0]) != std::string::npos) expected = "'" + expected;
    CHECK(parsed[0][i] == expected);
  }
}

TEST_CASE("StudySummary_KnownRatings_MatchIndependentComputation") {
  const StudyProtocol p = smallProtocol();
  // Ratings on the paper's scale. Participant means per item:
  //   shape:   n1 (1+2)/2=1.5, n2 (1+1)/2=1, m1 (2+4)/2=3, m2 (1+2)/2=1.5
  //   context: n1 1, n2 2, m1 1, m2 3   (each participant rates both structures the same)
  std::vector<StudyResponseRow> rows;
  auto add = [&](const char* who, const char* group, int shapeC, int shapeS, int ctx) {
    rows.push_back(row(who, group, "cochlea", "shape", shapeC));
    rows.push_back(row(who, group, "stapes", "shape", shapeS));
    rows.push_back(row(who, group, "cochlea", "context", ctx));
    rows.push_back(row(who, group, "stapes", "context", ctx));
  };
  add("n1", "non-medical", 1, 2, 1);
  add("n2", "non-medical", 1, 1, 2);
  add("m1", "medical", 2, 4, 1);
  add("m2", "medical", 1, 2, 3);
  const StudySummary s = summariseStudy(p, rows);
  REQUIRE(s.columns == std::vector<std::string>{"non-medical", "medical", "all"});
  // shape / all: values 1.5, 1, 3, 1.5 → mean 1.75, SD sqrt(((−.25)²+(−.75)²+(1.25)²+(−.25)²)/3)
  const SummaryCell& shapeAll = s.at(0, 2);
  CHECK(shapeAll.stats.n == 4);
  CHECK(shapeAll.stats.mean == doctest::Approx(1.75));
  const double sd = std::sqrt((0.0625 + 0.5625 + 1.5625 + 0.0625) / 3.0);
  CHECK(shapeAll.stats.sd == doctest::Approx(sd));
  CHECK(shapeAll.stats.ciHigh == doctest::Approx(1.75 + 3.182446 * sd / 2.0).epsilon(1e-5));
  // Wilcoxon vs 3: differences −1.5, −2, 0 (dropped), −1.5 → ranks 1.5, 3, 1.5, all negative:
  // W+ = 0. Exact: 8 sign patterns of ranks {1.5,1.5,3}; W+ ∈ {0,1.5,1.5,3,3,4.5,4.5,6}; mean 3;
  // |W+ − 3| ≥ 3 only for 0 and 6 → p = 2/8.
  CHECK(shapeAll.stats.nonZero == 3);
  CHECK(shapeAll.stats.wPlus == doctest::Approx(0.0));
  CHECK(shapeAll.stats.pValue == doctest::Approx(0.25));
  CHECK(shapeAll.preferred == "none");
  // context / medical: 1 and 3 → mean 2, n 2.
  CHECK(s.at(1, 1).stats.mean == doctest::Approx(2.0));
  CHECK(s.at(1, 1).stats.n == 2);
  // Deterministic text outputs.
  CHECK(summaryCsv(s) == summaryCsv(summariseStudy(p, rows)));
  CHECK(summaryMarkdown(p, s, 4, 0).find("| shape |") != std::string::npos);
}

TEST_CASE("StudySummary_EmptyStudy_HasEmptyCellsAndStillRenders") {
  const StudyProtocol p = smallProtocol();
  const StudySummary s = summariseStudy(p, {});
  for (const auto& c : s.cells) CHECK(c.stats.n == 0);
  CHECK(summaryCsv(s).find("shape,all,0,") != std::string::npos);
  CHECK(summarySvg(p, s).find("<svg") == 0);
}

TEST_CASE("SummarySvg_LabelsItemsAxisAndLegend") {
  const StudyProtocol p = smallProtocol();
  std::vector<StudyResponseRow> rows;
  for (const char* who : {"a", "b", "c"}) {
    rows.push_back(row(who, "medical", "cochlea", "shape", 1));
    rows.push_back(row(who, "medical", "cochlea", "context", 4));
  }
  const std::string svg = summarySvg(p, summariseStudy(p, rows));
  for (const char* text : {">shape<", ">context<", ">prefer wdt<", ">prefer bare<", ">non-medical<", ">medical<", ">all<"}) {
    CAPTURE(text);
    CHECK(svg.find(text) != std::string::npos);
  }
  // The medical marker of "shape" sits at 1 on the axis.
  const ChartLayout layout;
  const std::string marker = "<rect x=\"" + std::to_string(layout.xOf(1.0, p.scale) - 5) + "\" y=\"" +
                             std::to_string(layout.yOf(0, 1, 3) - 5) + "\"";
  CHECK(svg.find(marker) != std::string::npos);
}

TEST_CASE("LongAndWideCsv_PartialParticipantAndHostileComment_RoundTrip") {
  const StudyProtocol p = smallProtocol();
  auto r1 = row("=cmd|' /C calc'!A0", "medical", "cochlea", "shape", 2);
  r1.comment = "Looks \"great\",\nbut =SUM(A1) — ça va?";
  r1.participantComplete = false;
  const std::string longCsv = responsesLongCsv({r1});
  const auto parsed = parseCsv(longCsv);
  REQUIRE(parsed.size() == 2);
  CHECK(parsed[1][0] == "'=cmd|' /C calc'!A0");
  CHECK(parsed[1][20] == r1.comment);
  // participant_complete (columns added later, such as the render quality, come after it).
  const auto complete = std::find(parsed[0].begin(), parsed[0].end(), "participant_complete");
  REQUIRE(complete != parsed[0].end());
  CHECK(parsed[1][std::size_t(complete - parsed[0].begin())] == "0");
  CHECK(parsed[0].back() == "settle_ms");
  CHECK(parsed[1].back().empty());  // the quality a participant saw: not known for this row
  const auto wide = parseCsv(responsesWideCsv(p, {r1}));
  REQUIRE(wide.size() == 2);
  CHECK(wide[0].size() == wide[1].size());
  CHECK(wide[1][2] == "0");
  CHECK(responsesLongJsonSidecar(p).find("\"rating_ab\"") != std::string::npos);
}

TEST_CASE("StudySummary_OneParticipant_HasNoSpreadAndNoEvidence") {
  const StudyProtocol p = smallProtocol();
  // One participant rating 1 everywhere: mean 1, SD undefined (reported 0, interval collapsed),
  // and the exact Wilcoxon p-value with a single non-zero difference is 1 (W+ = 0 or 1 equally likely).
  std::vector<StudyResponseRow> rows = {row("solo", "medical", "cochlea", "shape", 1),
                                        row("solo", "medical", "stapes", "shape", 1)};
  const StudySummary s = summariseStudy(p, rows);
  const SummaryCell& cell = s.at(0, 2);
  CHECK(cell.stats.n == 1);
  CHECK(cell.stats.mean == doctest::Approx(1.0));
  CHECK(cell.stats.sd == 0.0);
  CHECK(cell.stats.ciLow == cell.stats.ciHigh);
  CHECK(cell.stats.pValue == doctest::Approx(1.0));
  CHECK(cell.preferred == "none");
  CHECK(summaryCsv(s).find("shape,all,1,1,,,,") != std::string::npos);
}

TEST_CASE("SummaryMarkdown_HostileTitleAndIds_StayLiteralText") {
  auto p = parseStudyProtocol(R"json({"id": "s|x", "title": "# Pwned <img src=x onerror=alert(1)>\n| a | b |",
    "dataset": "phantom", "structures": ["cochlea"], "conditions": [{"id": "wdt"}, {"id": "bare"}],
    "items": [{"id": "sh`ape", "wording": "**Shape?** [link](javascript:x)"}], "groups": ["g"]})json",
                              "hostile.json");
  REQUIRE_MESSAGE(p, p.error().message);
  const StudySummary s = summariseStudy(*p, {});
  const std::string md = summaryMarkdown(*p, s, 0, 0);
  const std::string firstLine = md.substr(0, md.find('\n'));
  CHECK(firstLine == "# \\# Pwned &lt;img src=x onerror=alert\\(1\\)&gt; \\| a \\| b \\|");
  CHECK(md.find("<img") == std::string::npos);
  CHECK(md.find("Study s\\|x on dataset phantom") != std::string::npos);
  CHECK(md.find("- sh\\`ape: \\*\\*Shape?\\*\\* \\[link\\]\\(javascript:x\\)") != std::string::npos);
  CHECK(markdownText("a\r\nb\x1b[2J") == "a  b\\[2J");
}
