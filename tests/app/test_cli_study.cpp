#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <thread>
#include <tuple>

#include <nlohmann/json.hpp>

#include "quiz/study_design.h"
#include "quiz/study_protocol.h"
#include "quiz/study_report.h"
#include "test_databases.h"
#include "redcap_rules.h"
#include "test_support.h"
#include "volume/png_image.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

// Writes an answers file: for every structure, each item rated `rating(position)` as shown.
// With `nameTrials`, each line names its structure ("trial": s + 1).
void writeAnswers(const fs::path& path, int structures, const std::function<int(int)>& rating, const std::string& comment = "",
                  int stopAfter = -1, bool nameTrials = false) {
  std::ofstream out(path);
  for (int s = 0; s < structures && (stopAfter < 0 || s < stopAfter); ++s) {
    nlohmann::json j;
    if (nameTrials) j["trial"] = s + 1;
    const int r = rating(s);
    j["ratings"] = {{"shape", r}, {"context", r}, {"localization", r}, {"utility", r}};
    j["view_ms_a"] = 1000 + s;
    j["view_ms_b"] = 2000 + s;
    j["toggles"] = s % 3;
    if (!comment.empty()) j["comment"] = comment;
    out << j.dump() << "\n";
  }
}

}  // namespace

TEST_CASE("StudyCli_ScriptedParticipants_ExportIsCompleteDeterministicAndUnblinded") {
  test::TempDir dir;
  const std::string db = "--db '" + (dir / "study.db").string() + "'";
  const std::string study = "wdt_vs_bare_phantom";
  // P1 always prefers A as shown (so, unblinded, a mix); P2 rates 2 everywhere; P3 stops after 5
  // structures with a hostile comment.
  writeAnswers(dir / "p1.jsonl", 13, [](int) { return 1; });
  writeAnswers(dir / "p2.jsonl", 13, [](int) { return 2; });
  writeAnswers(dir / "p3.jsonl", 13, [](int) { return 4; }, "=HYPERLINK(\"x\"), \"quoted\"\nnew line — ünïcode", 5);
  for (auto [who, group] : std::map<std::string, std::string>{{"p1", "medical"}, {"p2", "non-medical"}, {"p3", "medical"}}) {
    auto r = test::runApp("study run " + study + " --participant " + who + " --group " + group + " --answers '" +
                          (dir / (who + ".jsonl")).string() + "' " + db);
    CAPTURE(r.err);
    REQUIRE(r.exitCode == 0);
    CHECK(r.out.find("cochlea") == std::string::npos);  // blinded: no structure names
    CHECK(r.out.find("wdt") == std::string::npos);
  }
  auto status = test::runApp("study status " + study + " " + db);
  CHECK(status.exitCode == 0);
  CHECK(status.out.find("p3") != std::string::npos);
  CHECK(status.out.find("20/52") != std::string::npos);

  auto e1 = test::runApp("study export " + study + " --out '" + (dir / "e1").string() + "' " + db);
  auto e2 = test::runApp("study export " + study + " --out '" + (dir / "e2").string() + "' " + db);
  REQUIRE(e1.exitCode == 0);
  REQUIRE(e2.exitCode == 0);
  CHECK(e1.err.find("[10/10] summary.png") != std::string::npos);  // progress shown
  for (const char* f : {"responses_long.csv", "responses_wide.csv", "responses_long.json", "redcap_dictionary.csv",
                        "redcap_records.csv", "redcap_repeating_forms.csv", "summary.csv", "summary.md", "summary.svg",
                        "summary.png"}) {
    CAPTURE(f);
    REQUIRE(fs::exists(dir / "e1" / f));
    CHECK(test::readFile(dir / "e1" / f) == test::readFile(dir / "e2" / f));  // exporting twice gives identical bytes
  }
  const auto rows = quiz::parseCsv(test::readFile(dir / "e1" / "responses_long.csv"));
  REQUIRE(rows.size() == 1 + 13 * 4 * 2 + 5 * 4);
  const auto& header = rows[0];
  auto col = [&](const std::string& name) {
    return std::size_t(std::find(header.begin(), header.end(), name) - header.begin());
  };
  std::map<std::string, int> p3Rows;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const auto& r = rows[i];
    const std::string who = r[col("participant_id")];
    const int shown = std::stoi(r[col("rating_ab")]);
    const int paper = std::stoi(r[col("rating")]);
    const bool aIsWdt = r[col("a_condition")] == "wdt";
    CHECK(paper == (aIsWdt ? shown : 6 - shown));
    CHECK(std::stod(r[col("alpha")]) > 1.0);  // the WDT preset's distance normalisation (> 1)
    CHECK(r[col("t")] == "0.15");
    if (who == "p3") {
      ++p3Rows[r[col("structure")]];
      CHECK(r[col("participant_complete")] == "0");
      CHECK(r[col("comment")] == "'=HYPERLINK(\"x\"), \"quoted\"\nnew line — ünïcode");
    }
  }
  CHECK(p3Rows.size() == 5);
  const std::string md = test::readFile(dir / "e1" / "summary.md");
  CHECK(md.find("3 participant(s), of whom 1 stopped before the end") != std::string::npos);
  // The REDCap files import: checked against REDCap's rules.
  const auto problems = test::checkRedcapImport(test::readFile(dir / "e1" / "redcap_dictionary.csv"),
                                                test::readFile(dir / "e1" / "redcap_records.csv"),
                                                test::readFile(dir / "e1" / "redcap_repeating_forms.csv"));
  std::string listed;
  for (const auto& problem : problems) listed += problem + "\n";
  CHECK_MESSAGE(problems.empty(), listed);
  CHECK(quiz::parseCsv(test::readFile(dir / "e1" / "redcap_records.csv")).size() == 1 + 3 + 13 * 4 * 2 + 5 * 4);

  // The chart PNG is the SVG with its text: dark glyph pixels left of the axis on every item's row,
  // under the axis (scale numbers) and in the legend; each group's marker at its mean.
  auto png = readPng((dir / "e1" / "summary.png").string());
  REQUIRE(png.has_value());
  const quiz::ChartLayout layout;
  CHECK(png->width == layout.width);
  CHECK(png->height == layout.height(4));
  auto darkIn = [&](int x0, int y0, int x1, int y1) {
    int n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) {
        const std::uint8_t* q = png->pixel(x, y);
        n += (q[0] < 110 && q[1] < 110 && q[2] < 110) ? 1 : 0;
      }
    return n;
  };
  for (int item = 0; item < 4; ++item) {
    CAPTURE(item);
    const int rowMiddle = layout.top + item * layout.rowHeight + layout.rowHeight / 2;
    CHECK(darkIn(5, rowMiddle - 12, layout.left - 20, rowMiddle + 8) > 20);  // the item's name
  }
  const int axisBottom = layout.top + 4 * layout.rowHeight;
  CHECK(darkIn(layout.left - 10, axisBottom + 5, png->width - 10, axisBottom + 24) > 20);  // scale numbers
  CHECK(darkIn(0, 0, png->width, 30) > 50);                                              // the title
  const auto summaryRows = quiz::parseCsv(test::readFile(dir / "e1" / "summary.csv"));
  for (std::size_t i = 1; i < summaryRows.size(); ++i) {
    const auto& r = summaryRows[i];  // item, group, n, mean, …
    if (r[2] == "0") continue;
    const std::size_t item = std::size_t(i - 1) / 3, column = std::size_t(i - 1) % 3;
    const int x = layout.xOf(std::stod(r[3]), quiz::StudyScale{}), y = layout.yOf(item, column, 3);
    CAPTURE(r[0]);
    CAPTURE(r[1]);
    const std::uint8_t* q = png->pixel(x, y);
    const auto colour = quiz::chartColumnColour(column);
    CHECK(std::abs(int(q[0]) - colour[0]) + std::abs(int(q[1]) - colour[1]) + std::abs(int(q[2]) - colour[2]) < 30);
  }
}

TEST_CASE("StudyCli_XapiExport_EveryRatingALikertStatementOnTheStudyScale") {
  test::TempDir dir;
  const std::string db = " --db '" + (dir / "s.db").string() + "'";
  writeAnswers(dir / "a.jsonl", 13, [](int s) { return 1 + s % 5; });
  REQUIRE(test::runApp("study run wdt_vs_bare_phantom --participant p1 --group medical --answers '" +
                       (dir / "a.jsonl").string() + "'" + db)
              .exitCode == 0);
  auto r = test::runApp("xapi --study wdt_vs_bare_phantom --homepage https://lms.example.edu --out '" +
                        (dir / "study.json").string() + "'" + db);
  CAPTURE(r.err);
  REQUIRE(r.exitCode == 0);
  CHECK(r.out.find("statements of 52 ratings") != std::string::npos);
  const auto statements = nlohmann::json::parse(test::readFile(dir / "study.json"));
  REQUIRE(statements.size() == 52);
  std::set<std::string> ids;
  for (const auto& s : statements) {
    ids.insert(s.at("id").get<std::string>());
    const auto& definition = s.at("object").at("definition");
    CHECK(definition.at("interactionType") == "likert");
    CHECK(definition.at("scale").size() == 5);
    const int response = std::stoi(s.at("result").at("response").get<std::string>());
    CHECK(response >= 1);
    CHECK(response <= 5);
    CHECK(s.at("actor").at("account").at("name") == "p1");
    CHECK(s.at("actor").at("account").at("homePage") == "https://lms.example.edu");
  }
  CHECK(ids.size() == 52);
  auto both = test::runApp("xapi --study wdt_vs_bare_phantom --user p1 --out '" + (dir / "x.json").string() + "'" + db);
  CHECK(both.exitCode == 1);
  auto badHome = test::runApp("xapi --homepage lms --out '" + (dir / "x.json").string() + "'" + db);
  CHECK(badHome.exitCode == 1);
  CHECK(badHome.err.find("xAPI home page 'lms'") != std::string::npos);
  auto noStudy = test::runApp("xapi --study none --out '" + (dir / "x.json").string() + "'" + db);
  CHECK(noStudy.exitCode == 1);
  CHECK(noStudy.err.find("no study 'none'") != std::string::npos);
}

TEST_CASE("StudyCli_StudyOnARealCtWithoutWrittenPresets_RunsOnDerivedPresets") {
  // The TotalSegmentator sample imported as 'abdomen': no preset is written for its structures,
  // so the study's are derived from the CT's own intensities (render/derived_preset.h).
  if (!test::requireSharedData("a study on the real CT")) return;
  test::TempDir dir;
  const std::string db = " --db '" + (dir / "s.db").string() + "'";
  auto imported = test::runApp("import --volume '" + test::sharedData("totalsegmentator/ct_small.nii.gz").string() +
                               "' --labels '" + test::sharedData("totalsegmentator/seg_small.nii.gz").string() +
                               "' --names '" + test::sharedData("totalsegmentator/labels.json").string() +
                               "' --name abdomen" + db);
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  auto protocolWith = [&](const std::string& id, const std::vector<std::string>& structures) {
    nlohmann::json p = {{"schema", 1}, {"id", id}, {"title", "Abdomen"}, {"dataset", "abdomen"},
                        {"structures", structures},
                        {"conditions", {{{"id", "wdt"}, {"label", "WDT"}, {"preset_suffix", "_wdt"}},
                                        {{"id", "bare"}, {"label", "bare"}, {"preset_suffix", "_bare"}}}},
                        {"items", {{{"id", "shape"}, {"wording", "Shape?"}}, {{"id", "context"}, {"wording", "Context?"}},
                                   {{"id", "localization"}, {"wording", "Where?"}}, {{"id", "utility"}, {"wording", "Useful?"}}}},
                        {"scale", {{"min", 1}, {"max", 5}, {"anchors", {{"1", "A"}, {"3", "same"}, {"5", "B"}}}}},
                        {"groups", {"medical"}}, {"seed", 7}, {"t", 0.5}};
    const fs::path file = dir / (id + ".json");
    std::ofstream(file) << p.dump(2);
    return file.string();
  };
  const std::vector<std::string> organs = {"liver", "spleen", "kidney_left"};
  for (const auto& organ : organs) REQUIRE_FALSE(fs::exists(test::sourceDir() / "data" / "presets" / (organ + "_wdt.json")));
  writeAnswers(dir / "a.jsonl", 3, [](int s) { return 1 + s; });
  const std::string answers = " --answers '" + (dir / "a.jsonl").string() + "'";
  auto run = test::runApp("study run '" + protocolWith("abdomen_study", organs) + "' --participant p1 --group medical" +
                          answers + db);
  CAPTURE(run.err);
  REQUIRE(run.exitCode == 0);
  CHECK(run.out.find("all 3 structures rated") != std::string::npos);
  auto exported = test::runApp("study export abdomen_study --out '" + (dir / "export").string() + "'" + db);
  REQUIRE(exported.exitCode == 0);
  const auto rows = quiz::parseCsv(test::readFile(dir / "export" / "responses_long.csv"));
  CHECK(rows.size() == 1 + 3 * 4);

  // A structure the dataset does not have: refused before anyone is enrolled, naming it.
  auto missing = test::runApp("study run '" + protocolWith("abdomen_brain", {"liver", "brain"}) +
                              "' --participant p2 --group medical" + answers + db);
  CHECK(missing.exitCode == 1);
  CHECK(missing.err.find("structure 'brain'") != std::string::npos);
  CHECK(std::count(missing.err.begin(), missing.err.end(), '\n') == 1);
  auto status = test::runApp("study status abdomen_brain" + db);
  CHECK(status.out.find("0 participant") != std::string::npos);
}

TEST_CASE("StudyCli_EmptyStudyExport_WritesHeadersOnly") {
  test::TempDir dir;
  auto r = test::runApp("study export wdt_vs_bare_phantom --out '" + (dir / "out").string() + "' --db '" +
                        (dir / "s.db").string() + "'");
  REQUIRE(r.exitCode == 0);
  CHECK(quiz::parseCsv(test::readFile(dir / "out" / "responses_long.csv")).size() == 1);
}

TEST_CASE("StudyCli_MalformedAnswerLine_ReportsLineAndKeepsEarlierRatings") {
  test::TempDir dir;
  {
    std::ofstream out(dir / "a.jsonl");
    out << R"({"ratings": {"shape": 1, "context": 1, "localization": 1, "utility": 1}})" << "\n";
    out << R"({"ratings": {"shape": 9, "context": 1, "localization": 1, "utility": 1}})" << "\n";
  }
  const std::string db = "--db '" + (dir / "s.db").string() + "'";
  auto r = test::runApp("study run wdt_vs_bare_phantom --participant x --group medical --answers '" +
                        (dir / "a.jsonl").string() + "' " + db);
  CHECK(r.exitCode != 0);
  CHECK(r.err.find("a.jsonl:2") != std::string::npos);
  CHECK(r.err.find("ratings.shape") != std::string::npos);
  auto status = test::runApp("study status wdt_vs_bare_phantom " + db);
  CHECK(status.out.find("4/52") != std::string::npos);
}

// Every exported rating of `who` carries the answers line written for its presentation position
// (writeAnswers: view_ms_a = 1000 + position - 1, rating as shown = 1 + (position - 1) % 5);
// returns how many rows `who` has.
std::size_t checkAnswersOnTheirTrials(const fs::path& exportDir, const std::string& who) {
  const auto rows = quiz::parseCsv(test::readFile(exportDir / "responses_long.csv"));
  REQUIRE(!rows.empty());
  const auto& header = rows[0];
  auto col = [&](const std::string& name) {
    return std::size_t(std::find(header.begin(), header.end(), name) - header.begin());
  };
  std::size_t mine = 0;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    if (rows[i][col("participant_id")] != who) continue;
    ++mine;
    const int position = std::stoi(rows[i][col("presentation_order")]);
    CAPTURE(position);
    CHECK(std::stod(rows[i][col("view_ms_a")]) == 1000 + position - 1);
    CHECK(std::stoi(rows[i][col("rating_ab")]) == 1 + (position - 1) % 5);
  }
  return mine;
}

TEST_CASE("StudyCli_ResumeAfterAStop_AnswersStayOnTheTrialsTheyName") {
  // A run stops after 5 structures (a server drop, answers ran out); the same command is run again
  // with the whole file. Answers must stay on their structures: an unnamed file is refused for a
  // resumed participant (it used to put lines 1–8 on structures 6–13 and call the study complete),
  // a file naming its trials completes the participant, each answer where its line says.
  test::TempDir dir;
  const std::string db = " --db '" + (dir / "s.db").string() + "'", study = "wdt_vs_bare_phantom";
  const auto rating = [](int s) { return 1 + s % 5; };
  const auto run = [&](const std::string& who, const std::string& file) {
    return test::runApp("study run " + study + " --participant " + who + " --group medical --answers '" +
                        (dir / file).string() + "'" + db);
  };
  writeAnswers(dir / "first5.jsonl", 13, rating, "", 5);
  writeAnswers(dir / "all.jsonl", 13, rating);
  REQUIRE(run("unnamed", "first5.jsonl").exitCode == 0);
  auto resumed = run("unnamed", "all.jsonl");
  CHECK(resumed.exitCode != 0);
  CHECK(resumed.err.find("all.jsonl:1") != std::string::npos);
  CHECK(resumed.err.find("\"trial\"") != std::string::npos);
  CHECK(std::count(resumed.err.begin(), resumed.err.end(), '\n') == 1);
  CHECK(resumed.out.find("all 13 structures rated") == std::string::npos);

  // Named trials: the resumed file, lines shuffled, fills exactly the 8 structures left.
  writeAnswers(dir / "named5.jsonl", 13, rating, "", 5, true);
  writeAnswers(dir / "named.jsonl", 13, rating, "", -1, true);
  {
    std::vector<std::string> lines;
    std::istringstream in(test::readFile(dir / "named.jsonl"));
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    std::reverse(lines.begin(), lines.end());
    std::ofstream out(dir / "named_reversed.jsonl");
    for (const auto& line : lines) out << line << "\n";
  }
  REQUIRE(run("named", "named5.jsonl").exitCode == 0);
  auto completed = run("named", "named_reversed.jsonl");
  CAPTURE(completed.err);
  CHECK(completed.exitCode == 0);
  CHECK(completed.out.find("all 13 structures rated") != std::string::npos);
  auto again = run("named", "named.jsonl");  // a third run changes nothing
  CHECK(again.exitCode == 0);

  auto exported = test::runApp("study export " + study + " --out '" + (dir / "export").string() + "'" + db);
  REQUIRE(exported.exitCode == 0);
  CHECK(checkAnswersOnTheirTrials(dir / "export", "unnamed") == 5 * 4);
  CHECK(checkAnswersOnTheirTrials(dir / "export", "named") == 13 * 4);

  // A named file with a trial twice or out of range: one line naming it.
  {
    std::ofstream out(dir / "twice.jsonl");
    const std::string line = R"({"trial": 2, "ratings": {"shape": 1, "context": 1, "localization": 1, "utility": 1}})";
    out << line << "\n" << line << "\n";
  }
  auto twice = run("twice", "twice.jsonl");
  CHECK(twice.exitCode != 0);
  CHECK(twice.err.find("twice.jsonl:2: trial 2 is answered twice") != std::string::npos);
  {
    std::ofstream out(dir / "range.jsonl");
    out << R"({"trial": 14, "ratings": {"shape": 1, "context": 1, "localization": 1, "utility": 1}})" << "\n";
  }
  auto range = run("range", "range.jsonl");
  CHECK(range.exitCode != 0);
  CHECK(range.err.find("range.jsonl:1: 'trial' must be") != std::string::npos);
}

TEST_CASE("StudyCli_BadArguments_OneLineErrors") {
  test::TempDir dir;
  const std::string db = " --db '" + (dir / "s.db").string() + "'";
  writeAnswers(dir / "a.jsonl", 13, [](int) { return 3; });
  // The terminal shows no renderings: without answers from elsewhere nobody is enrolled.
  auto noAnswers = test::runApp("study run wdt_vs_bare_phantom --participant a --group medical" + db, "a\nb\n\n1\n");
  CHECK(noAnswers.exitCode == 1);
  CHECK(noAnswers.err.find("cannot show the renderings") != std::string::npos);
  CHECK(noAnswers.err.find("desktop") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "s.db"));
  auto missingAnswers = test::runApp("study run wdt_vs_bare_phantom --participant a --group medical --answers '" +
                                     (dir / "none.jsonl").string() + "'" + db);
  CHECK(missingAnswers.exitCode == 1);
  CHECK(missingAnswers.err.find("none.jsonl") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "s.db"));
  const std::string answers = " --answers '" + (dir / "a.jsonl").string() + "'";
  auto noStudy = test::runApp("study run nonexistent_study --participant a --group medical" + answers + db);
  CHECK(noStudy.exitCode != 0);
  CHECK(noStudy.err.find("nonexistent_study") != std::string::npos);
  auto badGroup = test::runApp("study run wdt_vs_bare_phantom --participant a --group pilots" + answers + db);
  CHECK(badGroup.exitCode != 0);
  CHECK(badGroup.err.find("pilots") != std::string::npos);
  auto noOut = test::runApp("study export wdt_vs_bare_phantom" + db);
  CHECK(noOut.exitCode != 0);
}

TEST_CASE("StudyCli_ThreeLabMachinesOnOneClassServer_EachParticipantGetsTheirOwnCounterbalancingRow") {
  // Three `study run` processes at once against one PostgreSQL server, two participants each (the
  // shipped study is registered by whichever comes first); then one export from the server.
  auto url = test::freshPostgresDatabase("the class-server study test");
  if (!url) return;
  test::TempDir dir;
  const std::string study = "wdt_vs_bare_phantom", db = " --db '" + *url + "'";
  writeAnswers(dir / "answers.jsonl", 13, [](int s) { return 1 + s % 5; });
  std::vector<test::CommandResult> runs(6);
  std::vector<std::thread> machines;
  for (int m = 0; m < 3; ++m)
    machines.emplace_back([&, m] {
      for (int k = 0; k < 2; ++k)
        runs[std::size_t(2 * m + k)] =
            test::runApp("study run " + study + " --participant lab" + std::to_string(m) + "-p" + std::to_string(k) +
                         " --group " + (k ? "medical" : "non-medical") + " --answers '" +
                         (dir / "answers.jsonl").string() + "'" + db);
    });
  for (auto& t : machines) t.join();
  for (const auto& r : runs) {
    CAPTURE(r.err);
    CHECK(r.exitCode == 0);
    CHECK(r.out.find("all 13 structures rated") != std::string::npos);
  }
  auto status = test::runApp("study status " + study + db);
  CHECK(status.exitCode == 0);
  CHECK(status.out.find("6 participant(s)") != std::string::npos);

  auto exported = test::runApp("study export " + study + " --out '" + (dir / "export").string() + "'" + db);
  CAPTURE(exported.err);
  REQUIRE(exported.exitCode == 0);
  const auto rows = quiz::parseCsv(test::readFile(dir / "export" / "responses_long.csv"));
  REQUIRE(rows.size() == 1 + 6 * 13 * 4);
  const auto& header = rows[0];
  auto col = [&](const std::string& name) {
    return std::size_t(std::find(header.begin(), header.end(), name) - header.begin());
  };
  // Each participant's sequence (structure, order, condition shown as A) is a row of the design,
  // and the six participants got the first six rows: none twice, none skipped.
  using Plan = std::set<std::tuple<std::string, int, std::string>>;
  std::map<std::string, Plan> seen;
  for (std::size_t i = 1; i < rows.size(); ++i)
    seen[rows[i][col("participant_id")]].insert(
        {rows[i][col("structure")], std::stoi(rows[i][col("presentation_order")]), rows[i][col("a_condition")]});
  REQUIRE(seen.size() == 6);
  auto protocol = quiz::loadStudyProtocol((test::sourceDir() / "data/studies/paper_survey.json").string());
  REQUIRE(protocol.has_value());
  std::set<Plan> designRows, participantsRows;
  for (std::size_t row = 0; row < 6; ++row) {
    Plan plan;
    for (const auto& t : quiz::planParticipant(protocol->structures.size(), row, protocol->seed))
      plan.insert({protocol->structures[t.structureIndex], int(t.position) + 1,
                   protocol->conditions[t.aIsFirstCondition ? 0 : 1].id});
    designRows.insert(plan);
  }
  for (const auto& [who, plan] : seen) participantsRows.insert(plan);
  CHECK(participantsRows == designRows);
}

TEST_CASE("StudyCli_MergeLabMachinesFiles_OneStudyReportsBalanceRefusesConflictsAndMissingSources") {
  test::TempDir dir;
  const std::string study = "wdt_vs_bare_phantom";
  writeAnswers(dir / "answers.jsonl", 13, [](int s) { return 1 + s % 5; });
  const auto runOn = [&](const std::string& file, const std::string& who) {
    auto r = test::runApp("study run " + study + " --participant " + who + " --group medical --answers '" +
                          (dir / "answers.jsonl").string() + "' --db '" + (dir / file).string() + "'");
    CAPTURE(r.err);
    REQUIRE(r.exitCode == 0);
  };
  runOn("lab1.db", "a1");
  runOn("lab1.db", "a2");
  runOn("lab2.db", "b1");
  const std::string sources = " '" + (dir / "lab1.db").string() + "' '" + (dir / "lab2.db").string() + "'";
  const std::string into = " --db '" + (dir / "class.db").string() + "'";
  auto merged = test::runApp("study merge " + study + sources + into);
  CAPTURE(merged.err);
  REQUIRE(merged.exitCode == 0);
  CHECK(merged.out.find("lab1.db: 2 participant(s) added, 0 already there") != std::string::npos);
  CHECK(merged.out.find("lab2.db: 1 participant(s) added") != std::string::npos);
  CHECK(merged.out.find("3 participant(s)") != std::string::npos);
  CHECK(merged.out.find("NOT balanced") != std::string::npos);  // both machines used design row 0
  CHECK(merged.out.find("row 0 ×2") != std::string::npos);

  auto exported = test::runApp("study export " + study + " --out '" + (dir / "export").string() + "'" + into);
  REQUIRE(exported.exitCode == 0);
  CHECK(quiz::parseCsv(test::readFile(dir / "export" / "responses_long.csv")).size() == 1 + 3 * 13 * 4);
  CHECK(test::readFile(dir / "export" / "summary.csv").find("all") != std::string::npos);

  auto again = test::runApp("study merge " + study + sources + into);
  REQUIRE(again.exitCode == 0);
  CHECK(again.out.find("lab1.db: 0 participant(s) added, 2 already there") != std::string::npos);

  // Another person under an id lab 1 used, with other answers. (Identical answers run within the
  // same second export identically, and are then taken for the same records: the merge compares a
  // database's participant with the stored one by their exported lines when the raw rows differ.)
  writeAnswers(dir / "answers_other.jsonl", 13, [](int s) { return 5 - s % 5; });
  {
    auto r = test::runApp("study run " + study + " --participant a1 --group medical --answers '" +
                          (dir / "answers_other.jsonl").string() + "' --db '" + (dir / "lab3.db").string() + "'");
    CAPTURE(r.err);
    REQUIRE(r.exitCode == 0);
  }
  auto clash = test::runApp("study merge " + study + " '" + (dir / "lab3.db").string() + "'" + into);
  CHECK(clash.exitCode == 1);
  CHECK(clash.err.find("'a1'") != std::string::npos);
  CHECK(clash.err.find("nothing was merged") != std::string::npos);
  CHECK(std::count(clash.err.begin(), clash.err.end(), '\n') == 1);

  auto missing = test::runApp("study merge " + study + " '" + (dir / "nowhere.db").string() + "'" + into);
  CHECK(missing.exitCode == 1);
  CHECK(missing.err.find("nowhere.db") != std::string::npos);
  CHECK_FALSE(fs::exists(dir / "nowhere.db"));
  auto noTarget = test::runApp("study merge " + study + " '" + (dir / "nowhere.db").string() + "' --db '" +
                               (dir / "new.db").string() + "'");
  CHECK(noTarget.exitCode == 1);
  CHECK_FALSE(fs::exists(dir / "new.db"));  // a failed merge leaves no new database behind
  auto status = test::runApp("study status " + study + into);
  CHECK(status.out.find("3 participant(s)") != std::string::npos);
}

TEST_CASE("StudyCli_MergeExportFolders_SameSummaryAsMergedDatabasesBadBundleRefusedWithRowAndColumn") {
  test::TempDir dir;
  const std::string study = "wdt_vs_bare_phantom";
  writeAnswers(dir / "answers.jsonl", 13, [](int s) { return 1 + s % 5; });
  writeAnswers(dir / "other.jsonl", 13, [](int s) { return 5 - s % 3; });
  const auto runOn = [&](const std::string& file, const std::string& who, const std::string& answers) {
    auto r = test::runApp("study run " + study + " --participant " + who + " --group medical --answers '" +
                          (dir / answers).string() + "' --db '" + (dir / file).string() + "'");
    CAPTURE(r.err);
    REQUIRE(r.exitCode == 0);
  };
  runOn("lab1.db", "a1", "answers.jsonl");
  runOn("lab1.db", "a2", "other.jsonl");
  runOn("lab2.db", "b1", "other.jsonl");
  runOn("lab3.db", "c1", "answers.jsonl");
  for (const char* lab : {"lab1", "lab2", "lab3"}) {
    auto exported = test::runApp("study export " + study + " --out '" + (dir / lab).string() + "' --db '" +
                                 (dir / (std::string(lab) + ".db")).string() + "'");
    REQUIRE(exported.exitCode == 0);
  }
  const auto quotedPath = [&](const std::string& name) { return " '" + (dir / name).string() + "'"; };
  // The databases merged, for comparison.
  auto viaDatabases = test::runApp("study merge " + study + quotedPath("lab1.db") + quotedPath("lab2.db") +
                                   quotedPath("lab3.db") + " --db" + quotedPath("class.db"));
  REQUIRE(viaDatabases.exitCode == 0);
  REQUIRE(test::runApp("study export " + study + " --out" + quotedPath("from_databases") + " --db" +
                       quotedPath("class.db")).exitCode == 0);

  const std::string folders = quotedPath("lab1") + quotedPath("lab2") + quotedPath("lab3");
  auto merged = test::runApp("study merge " + study + folders + " --db" + quotedPath("bundles.db"));
  CAPTURE(merged.err);
  REQUIRE(merged.exitCode == 0);
  CHECK(merged.out.find("lab1: 2 participant(s) added, 0 already there") != std::string::npos);
  CHECK(merged.out.find("4 participant(s)") != std::string::npos);
  REQUIRE(test::runApp("study export " + study + " --out" + quotedPath("from_bundles") + " --db" +
                       quotedPath("bundles.db")).exitCode == 0);
  for (const char* file : {"summary.csv", "summary.md", "responses_long.csv", "responses_wide.csv", "redcap_records.csv"})
    CHECK_MESSAGE(test::readFile(dir / "from_bundles" / file) == test::readFile(dir / "from_databases" / file), file);
  auto again = test::runApp("study merge " + study + folders + quotedPath("lab2.db") + " --db" + quotedPath("bundles.db"));
  REQUIRE(again.exitCode == 0);
  CHECK(again.out.find("lab1: 0 participant(s) added, 2 already there") != std::string::npos);
  CHECK(again.out.find("lab2.db: 0 participant(s) added, 1 already there") != std::string::npos);

  // A bundle edited by hand: one bad cell names the file, the row and the column; nothing merged.
  fs::create_directories(dir / "edited");
  for (const char* file : {"responses_long.csv", "responses_long.json"})
    fs::copy_file(dir / "lab3" / file, dir / "edited" / file);
  std::string table = test::readFile(dir / "edited" / "responses_long.csv");
  const std::size_t third = table.find("\r\n", table.find("\r\n", table.find("\r\n") + 2) + 2) + 2;  // row 4
  const std::size_t ratingAt = [&] {
    std::size_t at = third;
    for (int comma = 0; comma < 5; ++comma) at = table.find(',', at) + 1;
    return at;
  }();
  table[ratingAt] = '9';
  { std::ofstream(dir / "edited" / "responses_long.csv", std::ios::binary) << table; }
  auto bad = test::runApp("study merge " + study + quotedPath("lab1") + quotedPath("edited") + " --db" +
                          quotedPath("fresh.db"));
  CHECK(bad.exitCode == 1);
  CHECK(bad.err.find("edited/responses_long.csv: row 4, column 'rating_ab': 9 is outside 1–5") != std::string::npos);
  CHECK(std::count(bad.err.begin(), bad.err.end(), '\n') == 1);
  auto none = test::runApp("study status " + study + " --db" + quotedPath("fresh.db"));
  CHECK(none.out.find("0 participant(s)") != std::string::npos);
  // A folder that is no export, and a bundle of another study.
  fs::create_directories(dir / "empty");
  auto notBundle = test::runApp("study merge " + study + quotedPath("empty") + " --db" + quotedPath("fresh.db"));
  CHECK(notBundle.exitCode == 1);
  CHECK(notBundle.err.find("empty/responses_long.json") != std::string::npos);
  std::string sidecar = test::readFile(dir / "edited" / "responses_long.json");
  sidecar.replace(sidecar.find(study), study.size(), "another_study");
  { std::ofstream(dir / "edited" / "responses_long.json", std::ios::binary) << sidecar; }
  auto otherStudy = test::runApp("study merge " + study + quotedPath("edited") + " --db" + quotedPath("fresh.db"));
  CHECK(otherStudy.exitCode == 1);
  CHECK(otherStudy.err.find("is of study 'another_study'") != std::string::npos);
}
