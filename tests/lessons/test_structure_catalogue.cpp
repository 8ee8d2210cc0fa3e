// The shipped structure catalogues (data/catalogues/*.json) and grading with them: properties over
// every entry of every catalogue, for questions that do and do not ask for the side.
#include <doctest/doctest.h>

#include <fstream>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "lessons/lesson_engine.h"
#include "lessons/structure_catalogue.h"
#include "quiz/grading.h"
#include "quiz/sided_names.h"
#include "test_support.h"
#include "volume/phantom.h"

using namespace at;
using namespace at::lessons;

namespace {

// The dataset's structures as the program names them: the phantom's own, the skull's from the
// label names its seeds file gives (scripts/label-scans.sh writes exactly these).
std::vector<Structure> structuresOf(const std::string& datasetId) {
  std::vector<Structure> out;
  if (datasetId == "phantom") {
    PhantomOptions options;
    options.size = 32;
    return makePhantom(options).structures;
  }
  REQUIRE(datasetId == "skull");
  std::ifstream in(std::string(AT_SOURCE_DIR) + "/data/segmentations/skull/seeds.json");
  REQUIRE(in.good());
  const auto seeds = nlohmann::json::parse(in);
  for (const auto& label : seeds["labels"]) {
    if (label["value"].get<int>() == 0) continue;
    Structure s;
    s.label = label["value"].get<std::uint16_t>();
    s.displayName = label["name"].get<std::string>();
    // The ids label-scans.sh gives: the name in snake case without brackets.
    for (char c : s.displayName) {
      if (std::isalnum(static_cast<unsigned char>(c))) s.id += char(std::tolower(static_cast<unsigned char>(c)));
      else if (!s.id.empty() && s.id.back() != '_') s.id += '_';
    }
    while (!s.id.empty() && s.id.back() == '_') s.id.pop_back();
    out.push_back(s);
  }
  return out;
}

quiz::ResolvedQuestion nameQuestion(const std::string& target, bool askSide) {
  quiz::ResolvedQuestion q;
  q.question.id = "catalogue.name";
  q.question.kind = quiz::QuestionKind::Name;
  q.question.target = target;
  q.question.askSide = askSide;
  return q;
}

quiz::Grade graded(const quiz::ResolvedQuestion& q, const std::string& text, const quiz::GradingContext& context) {
  quiz::Answer a;
  a.text = text;
  auto g = quiz::grade(q, a, context);
  REQUIRE(g.has_value());
  return *g;
}

}  // namespace

TEST_CASE("shippedCatalogues_EveryFileParses_AndNamesEveryStructureOfItsDataset") {
  std::set<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(AT_SOURCE_DIR) + "/data/catalogues")) {
    if (entry.path().extension() != ".json") continue;
    std::ifstream in(entry.path());
    std::stringstream text;
    text << in.rdbuf();
    auto parsed = parseStructureCatalogue(text.str(), entry.path().filename().string());
    REQUIRE_MESSAGE(parsed.has_value(), (parsed ? "" : parsed.error().message));
    files.insert(parsed->datasetId);
  }
  CHECK(files.size() == shippedCatalogues().size());
  for (const StructureCatalogue& catalogue : shippedCatalogues()) {
    CAPTURE(catalogue.datasetId);
    const std::vector<Structure> structures = structuresOf(catalogue.datasetId);
    CHECK(catalogue.entries.size() == structures.size());
    for (const Structure& s : structures) {
      CAPTURE(s.id);
      const CatalogueEntry* entry = catalogue.find(s.id);
      REQUIRE(entry != nullptr);
      // The catalogue's side agrees with the label name's, where the name says one.
      if (quiz::sideOfName(s.displayName) != quiz::Side::None) CHECK((entry->side == quiz::sideOfName(s.displayName)));
      CHECK_FALSE(entry->latin.empty());
    }
  }
}

TEST_CASE("parseStructureCatalogue_BadFiles_AreRefusedNamingTheField") {
  const auto error = [](const std::string& text) {
    auto parsed = parseStructureCatalogue(text, "cat.json");
    REQUIRE_FALSE(parsed.has_value());
    return parsed.error().message;
  };
  CHECK(error(R"js({"schema":1,"dataset":"d","structures":[{"id":"a","name":"Orbit","side":"up"}]})js") ==
        "cat.json: structures[0].side: must be \"left\" or \"right\" (leave it out for unpaired structures)");
  CHECK(error(R"js({"schema":1,"dataset":"d","structures":[{"id":"a","name":"Orbit (left)"}]})js").find("structures[0].name") !=
        std::string::npos);
  CHECK(error(R"js({"schema":1,"dataset":"d","structures":[{"id":"a","name":"A"},{"id":"a","name":"B"}]})js")
            .find("structures[1].id") != std::string::npos);
  CHECK(error(R"js({"schema":1,"dataset":"d","structures":[{"id":"a","name":"A","colour":1}]})js")
            .find("structures[0].colour: unknown field") != std::string::npos);
  CHECK(error(R"js({"schema":2,"dataset":"d","structures":[]})js").find("schema") != std::string::npos);
}

// Every catalogue entry, every spelling: without the side it is right when the side is not asked
// (and the feedback never names a side), partial with "Which side?" when asked; every other
// structure's names are wrong (a counterpart's too, when the side is asked).
TEST_CASE("gradingContext_EveryCatalogueEntry_SidelessRightOthersWrongSideAskedPartial") {
  std::size_t checked = 0;
  for (const StructureCatalogue& catalogue : shippedCatalogues()) {
    Course course;
    course.id = "catalogue_test";
    course.datasetId = catalogue.datasetId;  // no course synonyms: the catalogue alone must do
    const quiz::GradingContext context = gradingContext(structuresOf(catalogue.datasetId), course);
    for (const CatalogueEntry& entry : catalogue.entries) {
      std::vector<std::string> spellings = {entry.name};
      spellings.insert(spellings.end(), entry.synonyms.begin(), entry.synonyms.end());
      spellings.insert(spellings.end(), entry.latin.begin(), entry.latin.end());
      for (const std::string& spelling : spellings) {
        CAPTURE(catalogue.datasetId);
        CAPTURE(entry.structureId);
        CAPTURE(spelling);
        const quiz::Grade unasked = graded(nameQuestion(entry.structureId, false), spelling, context);
        CHECK(unasked.correct);
        CHECK(unasked.feedback.find("left") == std::string::npos);
        CHECK(unasked.feedback.find("right") == std::string::npos);
        const quiz::Grade asked = graded(nameQuestion(entry.structureId, true), spelling, context);
        if (entry.side == quiz::Side::None) {
          CHECK(asked.correct);
        } else {
          CHECK_FALSE(asked.correct);
          CHECK(asked.score == 0.5);
          CHECK(asked.feedback.rfind("Which side?", 0) == 0);
          const std::string sided = std::string(quiz::toString(entry.side)) + " " + spelling;
          CHECK(graded(nameQuestion(entry.structureId, true), sided, context).correct);
        }
        ++checked;
        for (const CatalogueEntry& other : catalogue.entries) {
          if (other.structureId == entry.structureId) continue;
          const bool counterpart = other.name == entry.name;
          CAPTURE(other.structureId);
          if (counterpart) {
            if (entry.side == quiz::Side::None) continue;
            const std::string otherSide = std::string(quiz::toString(other.side)) + " " + spelling;
            CHECK(graded(nameQuestion(other.structureId, true), otherSide, context).correct);
            CHECK_FALSE(graded(nameQuestion(entry.structureId, true), otherSide, context).correct);
            continue;
          }
          const quiz::Grade wrong = graded(nameQuestion(other.structureId, false), spelling, context);
          if (wrong.correct) {
            // Only a spelling both entries list (none in the shipped catalogues) may pass for both.
            FAIL_CHECK(spelling << " is accepted for " << other.structureId);
          }
        }
      }
    }
  }
  MESSAGE("catalogue spellings checked: " << checked);
  CHECK(checked > 100);
}
