// A typed name is graded the same on the class server as on the laptop: the server's SQL
// (at_grade_name, migration 20) against quiz::gradeName for the same keys and the same answers —
// exact names, typos, accents, articles, punctuation, side words, both sides, names of other
// structures and typos of them — on a synthetic catalogue and on the shipped courses' real catalogues
// (their names, synonyms, Latin names and sides), and a partly right answer keeps its partial
// score in an exam.
#include <doctest/doctest.h>

#include <array>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/class_exams.h"
#include "lessons/course_json.h"
#include "lessons/lesson_engine.h"
#include "lessons/structure_catalogue.h"
#include "quiz/grading.h"
#include "secure_class.h"
#include "test_support.h"
#include "volume/phantom.h"

using namespace at;
using namespace at::db;

namespace {

// Structures with paired sides, synonyms, names a typo apart, and an abbreviation.
quiz::GradingContext catalog() {
  quiz::GradingContext c;
  c.names = {{"orbit_right", {"Orbit (right)", "right orbital cavity"}, quiz::Side::Right, "Orbit"},
             {"orbit_left", {"Orbit (left)", "left orbital cavity"}, quiz::Side::Left, "Orbit"},
             {"stapes", {"Stapes", "stirrup"}, quiz::Side::None, ""},
             {"malleus", {"Malleus", "hammer"}, quiz::Side::None, ""},
             {"incus", {"Incus", "anvil"}, quiz::Side::None, ""},
             {"lateral_canal", {"Lateral semicircular canal", "horizontal canal"}, quiz::Side::None, ""},
             {"superior_canal", {"Superior semicircular canal", "anterior canal"}, quiz::Side::None, ""},
             {"ethmoid_sinus", {"Ethmoid sinus", "ethmoidal air cells"}, quiz::Side::None, ""},
             {"sphenoid_sinus", {"Sphenoid sinus"}, quiz::Side::None, ""},
             {"facial_nerve", {"Facial nerve", "CN VII", "nervus facialis"}, quiz::Side::None, ""},
             {"cochlea", {"Cochlea", "c\xc3\xb3" "clea"}, quiz::Side::None, ""}};
  return c;
}

quiz::ResolvedQuestion nameQuestion(const std::string& target, bool askSide, std::vector<std::string> synonyms = {}) {
  quiz::ResolvedQuestion q;
  q.question.id = "names." + target + (askSide ? ".sided" : "");
  q.question.kind = quiz::QuestionKind::Name;
  q.question.target = target;
  q.question.askSide = askSide;
  q.question.synonyms = std::move(synonyms);
  return q;
}

bool validUtf8(const std::string& text) {
  for (std::size_t i = 0; i < text.size();) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    const std::size_t length = c < 0x80 ? 1 : (c >> 5) == 0x6 ? 2 : (c >> 4) == 0xE ? 3 : (c >> 3) == 0x1E ? 4 : 0;
    if (length == 0 || i + length > text.size()) return false;
    for (std::size_t k = 1; k < length; ++k)
      if ((static_cast<unsigned char>(text[i + k]) & 0xC0) != 0x80) return false;
    i += length;
  }
  return true;
}

// A random change a hurried student might make to `text` (typed text is valid UTF-8: the server's
// driver takes nothing else, so an edit that would split a character is not made).
std::string mangled(std::string text, std::mt19937_64& random) {
  const std::vector<std::string> decorations = {"the ", "The ", "left ", "right ", "l ", "R ", " (left)", " (right)",
                                                " right", "  ", "-", ",", "\xc3\xa9", "\xc3\x89", "\xc3\x9f", "\xe2\x80\x99"};
  const int edits = int(random() % 4);
  for (int e = 0; e < edits && !text.empty(); ++e) {
    const std::string before = text;
    const std::size_t at = std::size_t(random() % text.size());
    switch (random() % 7) {
      case 0: text.erase(at, 1); break;
      case 1: text.insert(at, 1, char('a' + random() % 26)); break;
      case 2: text[at] = char('a' + random() % 26); break;
      case 3: if (at + 1 < text.size()) std::swap(text[at], text[at + 1]); break;
      case 4: text[at] = char(std::toupper(static_cast<unsigned char>(text[at]))); break;
      case 5: text = decorations[random() % decorations.size()] + text; break;
      default: text += decorations[random() % decorations.size()]; break;
    }
    if (!validUtf8(text)) text = before;
  }
  return text;
}

double serverScore(Database& admin, const ClassExamKey& key, const std::string& typed) {
  auto s = admin.prepare("SELECT at_grade_name(?1, ?2, ?3, ?4, ?5::boolean)");
  REQUIRE(s);
  s->bind(1, typed).bind(2, nlohmann::json(key.nameBodies).dump()).bind(3, nlohmann::json(key.competitorBodies).dump());
  s->bind(4, key.targetSide).bind(5, std::string(key.askSide ? "true" : "false"));
  auto row = s->step();
  REQUIRE_MESSAGE(row, (row ? "" : row.error().message));
  REQUIRE(*row);
  return s->real(0);
}

// How many compared answers the laptop graded right, partly right and wrong.
struct GradeTally {
  int compared = 0, right = 0, partial = 0, wrong = 0;
};

// Grades each typed answer to `q` on the laptop (quiz::gradeName) and on the server (key), checks
// that both give the same score, and counts the laptop's grades.
void compareGrades(Database& admin, const ClassExamKey& key, const quiz::ResolvedQuestion& q,
                   const quiz::GradingContext& context, const std::vector<std::string>& typed, GradeTally& tally) {
  for (const std::string& text : typed) {
    auto laptop = quiz::gradeName(q, text, context);
    REQUIRE(laptop);
    const double server = serverScore(admin, key, text);
    CAPTURE(q.question.id);
    CAPTURE(text);
    CAPTURE(laptop->feedback);
    CHECK(server == doctest::Approx(laptop->score));
    ++tally.compared;
    (laptop->score >= 1 ? tally.right : laptop->score > 0 ? tally.partial : tally.wrong) += 1;
  }
}

}  // namespace

TEST_CASE("ClassExamNames_TheServerGradesTypedNamesAsTheLaptopDoes_ForTyposAccentsAndSides") {
  auto url = test::freshPostgresDatabase("the class exam names test");
  if (!url) return;
  Database admin = test::openAt(*url);
  const std::uint64_t seed = test::freshSeed("ClassExamNames_TheServerGradesTypedNamesAsTheLaptopDoes");
  std::mt19937_64 random(seed);
  const quiz::GradingContext context = catalog();
  const std::vector<quiz::ResolvedQuestion> questions = {
      nameQuestion("orbit_right", true), nameQuestion("orbit_right", false), nameQuestion("stapes", false),
      nameQuestion("lateral_canal", false, {"LSC"}), nameQuestion("ethmoid_sinus", false),
      nameQuestion("facial_nerve", false), nameQuestion("cochlea", false)};
  // Every spelling of every structure, and a few fixed answers with known grades.
  std::vector<std::string> spellings = {"orbit", "Orbit, left", "left right orbit", "Óbrit", "stapez", "staples",
                                        "sphenoid sinuss", "ethmoid sinuss", "cn 7", "CN-VII", "lateral  canal",
                                        "Cochlea", "COCLEA", "", "   ", "the"};
  for (const quiz::NameEntry& e : context.names) spellings.insert(spellings.end(), e.names.begin(), e.names.end());
  GradeTally tally;
  for (const quiz::ResolvedQuestion& q : questions) {
    ClassExamKey key;
    setNameKey(key, q, context);
    std::vector<std::string> typed = spellings;
    for (int i = 0; i < 60; ++i) typed.push_back(mangled(spellings[random() % spellings.size()], random));
    compareGrades(admin, key, q, context, typed, tally);
  }
  // The answers must have tried every grade, or the comparison proves little.
  MESSAGE("seed " << seed << ": " << tally.compared << " answers compared, " << tally.right << " right, "
                  << tally.partial << " partly, " << tally.wrong << " wrong");
  CHECK(tally.right > 20);
  CHECK(tally.partial > 3);
  CHECK(tally.wrong > 20);
  CHECK(serverScore(admin, [&] { ClassExamKey k; setNameKey(k, questions[0], context); return k; }(), "orbit") == 0.5);
}

TEST_CASE("ClassExamNames_AnExamKeepsThePartialScoreOfANameWithoutItsSide") {
  auto url = test::freshPostgresDatabase("the class exam names test");
  if (!url) return;
  test::SecureClass c(*url);
  Database instructor = test::openAt(c.instructorUrl);
  Database eve = test::openAt(c.eveUrl);
  const quiz::GradingContext context = catalog();
  ClassExamOpening x;
  x.examId = "sides";
  x.courseId = "toy";
  x.title = "Sides";
  x.timeLimitS = 600;
  x.items = {{0, "name", "Name the marked structure, with its side.", {}, "3d", "{}", "iVBORw0KGgo="},
             {1, "name", "Name the marked structure.", {}, "3d", "{}", "iVBORw0KGgo="}};
  x.keys.resize(2);
  setNameKey(x.keys[0], nameQuestion("orbit_right", true), context);
  setNameKey(x.keys[1], nameQuestion("lateral_canal", false), context);
  for (ClassExamKey& k : x.keys) k.target = k.nameBodies.front();
  REQUIRE(openClassExam(instructor, c.code, x, std::nullopt));
  REQUIRE(startClassExam(eve, c.code, "sides", std::nullopt));
  REQUIRE(answerClassExam(eve, c.code, "sides", 0, {std::nullopt, "the orbit", std::nullopt, 0}, std::nullopt));
  REQUIRE(answerClassExam(eve, c.code, "sides", 1, {std::nullopt, "Lateral semicirclar canal", std::nullopt, 0}, std::nullopt));
  auto result = finishClassExam(eve, c.code, "sides", std::nullopt);
  REQUIRE(result);
  REQUIRE(result->items.size() == 2);
  CHECK_FALSE(result->items[0].correct);
  CHECK(result->items[0].score == doctest::Approx(0.5));
  CHECK(result->items[1].correct);  // one letter missing: forgiven, as on the laptop
  CHECK(result->score == doctest::Approx(0.75));
}

namespace {

// The structures of a shipped dataset as the laptop knows them: the phantom's own list; for the
// other datasets the catalogue's entries, each shown as its name with its side (as a labelled
// scan names them).
std::vector<Structure> shippedStructures(const lessons::StructureCatalogue& catalogue) {
  if (catalogue.datasetId == "phantom") return phantomStructures();
  std::vector<Structure> out;
  for (const lessons::CatalogueEntry& e : catalogue.entries) {
    Structure s;
    s.id = e.structureId;
    s.displayName = e.name + (e.side == quiz::Side::Left ? " (left)" : e.side == quiz::Side::Right ? " (right)" : "");
    out.push_back(s);
  }
  return out;
}

}  // namespace

TEST_CASE("ClassExamNames_OnTheShippedCoursesRealCatalogues_TheServerGradesEveryNameAsTheLaptop") {
  auto url = test::freshPostgresDatabase("the class exam names test");
  if (!url) return;
  Database admin = test::openAt(*url);
  const std::uint64_t seed = test::freshSeed("ClassExamNames_OnTheShippedCoursesRealCatalogues");
  std::mt19937_64 random(seed);
  int courses = 0, sided = 0;
  GradeTally tally;
  for (const auto& file : std::filesystem::directory_iterator(test::sourceDir() / "data" / "courses")) {
    if (file.path().extension() != ".json") continue;
    auto course = lessons::loadCourseJson(file.path());
    REQUIRE_MESSAGE(course, (course ? "" : course.error().message));
    const lessons::StructureCatalogue* catalogue = lessons::shippedCatalogue(course->datasetId);
    REQUIRE_MESSAGE(catalogue, "no shipped catalogue for " << course->datasetId);
    ++courses;
    const std::vector<Structure> structures = shippedStructures(*catalogue);
    const quiz::GradingContext context = lessons::gradingContext(structures, *course);
    // The course's own name questions, and a name question (with and without its side) on every
    // structure of the dataset.
    std::vector<quiz::ResolvedQuestion> questions;
    for (const lessons::Lesson& lesson : course->lessons)
      for (const lessons::Step& step : lesson.steps)
        if (step.kind == lessons::StepKind::Question && step.question.kind == quiz::QuestionKind::Name)
          questions.push_back({step.question, {}, -1, {}});
    const std::size_t ownQuestions = questions.size();
    for (const Structure& s : structures) {
      questions.push_back(nameQuestion(s.id, false));
      questions.push_back(nameQuestion(s.id, true));
    }
    // Every spelling the catalogue and the course know, with and without side words, and typos.
    std::vector<std::string> spellings = {"", "the", "left", "bone"};
    for (const quiz::NameEntry& e : context.names)
      for (const std::string& name : e.names) {
        spellings.push_back(name);
        spellings.push_back("left " + name);
        spellings.push_back(name + " (right)");
      }
    CAPTURE(file.path().filename().string());
    CHECK(ownQuestions > 0);
    for (const quiz::ResolvedQuestion& q : questions) {
      ClassExamKey key;
      setNameKey(key, q, context);
      sided += key.targetSide.empty() ? 0 : 1;
      std::vector<std::string> typed;
      for (int i = 0; i < 12; ++i) typed.push_back(spellings[random() % spellings.size()]);
      for (int i = 0; i < 12; ++i) typed.push_back(mangled(spellings[random() % spellings.size()], random));
      for (const quiz::NameEntry& e : context.names)  // the target's own names, as typed in a hurry
        if (e.structureId == q.question.target)
          for (const std::string& name : e.names) {
            typed.push_back(name);
            typed.push_back(mangled(name, random));
            typed.push_back((random() % 2 ? "right " : "left ") + mangled(name, random));
          }
      compareGrades(admin, key, q, context, typed, tally);
    }
  }
  MESSAGE("seed " << seed << ": " << courses << " courses, " << tally.compared << " answers compared, " << tally.right
                  << " right, " << tally.partial << " partly, " << tally.wrong << " wrong; " << sided << " keys with a side");
  CHECK(courses >= 2);
  CHECK(tally.right > 100);
  CHECK(tally.partial > 20);
  CHECK(tally.wrong > 100);
  CHECK(sided > 10);
}
