// The REDCap files of a study export against REDCap's documented import rules (redcap_rules.h).
#include <doctest/doctest.h>

#include "quiz/redcap_export.h"
#include "quiz/study_protocol.h"
#include "redcap_rules.h"
#include "test_support.h"

using namespace at::quiz;

namespace {

StudyProtocol paperSurvey() {
  auto p = loadStudyProtocol((at::test::sourceDir() / "data/studies/paper_survey.json").string());
  REQUIRE(p.has_value());
  return *p;
}

StudyResponseRow rating(const StudyProtocol& p, const std::string& who, const std::string& group, std::size_t s,
                        std::size_t item, int shown, bool aIsWdt) {
  StudyResponseRow r;
  r.participantId = who;
  r.group = group;
  r.session = 1;
  r.structure = p.structures[s];
  r.item = p.items[item].id;
  r.ratingAb = shown;
  r.rating = unblindRating(shown, aIsWdt, p.scale);
  r.aCondition = aIsWdt ? "wdt" : "bare";
  r.presentationOrder = int(s) + 1;
  r.presetA = p.presetFor(r.structure, aIsWdt ? 0 : 1);
  r.presetB = p.presetFor(r.structure, aIsWdt ? 1 : 0);
  r.t = 0.5;
  r.alpha = 1.6;
  r.beta = 1;
  r.viewMsA = 1234.5;
  r.viewMsB = 999;
  r.toggles = 3;
  r.responseMs = 800;
  r.timestampUtc = "2026-11-22T05:01:02Z";
  r.appVersion = "0.1.0";
  return r;
}

struct Export {
  std::string dictionary, records, repeating;
};

Export exportOf(const StudyProtocol& p, const std::vector<StudyParticipantRow>& participants,
                const std::vector<StudyResponseRow>& rows) {
  return {redcapDictionaryCsv(p), redcapRecordsCsv(p, participants, rows), redcapRepeatingFormsCsv()};
}

std::string joined(const std::vector<std::string>& problems) {
  std::string s;
  for (const auto& p : problems) s += p + "\n";
  return s;
}

}  // namespace

TEST_CASE("RedcapExport_PaperSurveyWithPartialAndEmptyParticipants_PassesREDCapsImportRules") {
  const StudyProtocol p = paperSurvey();
  std::vector<StudyParticipantRow> participants = {
      {"P01", "medical", 0, 1, true}, {"P02", "non-medical", 1, 2, false}, {"P03", "medical", 2, 1, false}};
  std::vector<StudyResponseRow> rows;
  for (std::size_t s = 0; s < p.structures.size(); ++s)
    for (std::size_t i = 0; i < p.items.size(); ++i) rows.push_back(rating(p, "P01", "medical", s, i, 1 + int(s % 5), s % 2 == 0));
  for (std::size_t i = 0; i < p.items.size(); ++i) {
    auto r = rating(p, "P02", "non-medical", 4, i, 2, false);
    r.session = i < 2 ? 1 : 2;  // resumed in a second session
    r.comment = "Looks \"great\",\nbut | pipes, =SUM(A1) — ça va?";
    r.viewingMeasured = i != 0;
    rows.push_back(r);
  }
  rows.back().session = 0;  // a rating from before sessions were kept: blank
  const Export e = exportOf(p, participants, rows);
  const auto problems = at::test::checkRedcapImport(e.dictionary, e.records, e.repeating);
  CHECK_MESSAGE(problems.empty(), joined(problems));

  const auto records = parseCsv(e.records);
  // One row per participant plus one per rating: P03 (nothing rated yet) still has its record.
  REQUIRE(records.size() == 1 + 3 + rows.size());
  const auto& h = records[0];
  auto col = [&](const std::string& name) { return std::size_t(std::find(h.begin(), h.end(), name) - h.begin()); };
  CHECK(records[1][col("participant_id")] == "P01");
  CHECK(records[1][col("participant_group")] == "2");  // "medical" is the second group
  CHECK(records[1][col("redcap_repeat_instrument")].empty());
  CHECK(records[2][col("redcap_repeat_instrument")] == "structure_rating");
  CHECK(records[2][col("redcap_repeat_instance")] == "1");
  CHECK(records[2][col("structure")] == "1");
  CHECK(records[2][col("rated_at")] == "2026-11-22 05:01:02");
  CHECK(records[2][col("participant_group")].empty());  // the participant form is not filled on rating rows
  // P02's comment survives as typed (REDCap is no spreadsheet: no formula guard).
  const auto p02 = std::find_if(records.begin(), records.end(), [&](const auto& r) {
    return r[col("participant_id")] == "P02" && r[col("redcap_repeat_instance")] == "1";
  });
  REQUIRE(p02 != records.end());
  CHECK((*p02)[col("comment")] == rows[p.structures.size() * p.items.size()].comment);
  CHECK((*p02)[col("view_ms_a")].empty());  // not measured: blank, not 0
  const auto& lastOfP02 = records[records.size() - 2];
  CHECK(lastOfP02[col("session")].empty());
  CHECK(lastOfP02[col("presentation_order")] == "5");
  CHECK(records.back()[col("participant_id")] == "P03");
}

TEST_CASE("RedcapExport_RatingChoices_ReadAsWordsOnBothScales") {
  const StudyProtocol p = paperSurvey();
  const auto dictionary = parseCsv(redcapDictionaryCsv(p));
  std::map<std::string, std::string> choices;
  for (const auto& r : dictionary) choices[r[0]] = r[5];
  CHECK(choices["rating"] ==
        "1, strongly prefer wdt | 2, somewhat prefer wdt | 3, no preference | 4, somewhat prefer bare | 5, strongly "
        "prefer bare");
  CHECK(choices["rating_ab"] ==
        "1, A is much better | 2, A is somewhat better | 3, No preference | 4, B is somewhat better | 5, B is much "
        "better");
  CHECK(choices["participant_group"] == "1, non-medical | 2, medical");
  CHECK(dictionary[1][0] == "participant_id");  // the record id comes first
}

TEST_CASE("RedcapRules_CatchTheFaultsOfTheOldExport") {
  // The checker must fail on the faults REDCap refuses, or it proves nothing about the export.
  const StudyProtocol p = paperSurvey();
  const std::vector<StudyParticipantRow> participants = {{"P01", "medical", 0, 1, true}};
  const std::vector<StudyResponseRow> rows = {rating(p, "P01", "medical", 0, 0, 2, true)};
  const Export good = exportOf(p, participants, rows);
  REQUIRE(at::test::checkRedcapImport(good.dictionary, good.records, good.repeating).empty());
  auto replaced = [](std::string text, const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    REQUIRE(at != std::string::npos);
    return text.replace(at, from.size(), to);
  };
  struct Case {
    const char* what;
    Export files;
    const char* mentions;
  };
  const std::vector<Case> cases = {
      {"text where a code belongs", {good.dictionary, replaced(good.records, "structure_rating,1,,,,,,1,", "structure_rating,1,,,,,,cochlea,"), good.repeating},
       "is not one of its choice codes"},
      {"an ISO timestamp", {good.dictionary, replaced(good.records, "2026-11-22 05:01:02", "2026-11-22T05:01:02Z"), good.repeating},
       "is not YYYY-MM-DD HH:MM:SS"},
      {"no repeating columns", {good.dictionary, replaced(good.records, "redcap_repeat_instrument,redcap_repeat_instance,", ""), good.repeating},
       "no redcap_repeat_instrument"},
      {"an upper-case field name", {replaced(good.dictionary, "\r\nsessions,", "\r\nSessions,"), good.records, good.repeating},
       "invalid characters"},
      {"a reserved name", {replaced(good.dictionary, "\r\nsessions,", "\r\nredcap_sessions,"), good.records, good.repeating},
       "reserved"},
      {"a repeating form not set", {good.dictionary, good.records, "form_name,custom_form_label\r\n"},
       "is not a repeating form"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.what);
    const auto problems = at::test::checkRedcapImport(c.files.dictionary, c.files.records, c.files.repeating);
    CHECK_MESSAGE(joined(problems).find(c.mentions) != std::string::npos, joined(problems));
  }
}
