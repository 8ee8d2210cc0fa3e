#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "quiz/grading.h"

using namespace at::quiz;

namespace {

// One structure's accepted spellings, with no side (these names carry none).
NameEntry spellings(std::string structureId, std::vector<std::string> names) {
  return NameEntry{.structureId = std::move(structureId), .names = std::move(names), .baseName = ""};
}

GradingContext phantomNames() {
  GradingContext c;
  c.names = {spellings("cochlea", {"Cochlea"}),
             spellings("vestibule", {"Vestibule"}),
             spellings("stapes", {"Stapes", "stirrup"}),
             spellings("incus", {"Incus", "anvil"}),
             spellings("malleus", {"Malleus", "hammer"}),
             spellings("superior_semicircular_canal", {"Superior semicircular canal", "anterior semicircular canal"}),
             spellings("posterior_semicircular_canal", {"Posterior semicircular canal"}),
             spellings("lateral_semicircular_canal", {"Lateral semicircular canal", "horizontal semicircular canal"}),
             spellings("facial_nerve", {"Facial nerve", "cranial nerve VII"})};
  return c;
}

ResolvedQuestion locate(const std::string& target, double toleranceMm) {
  ResolvedQuestion q;
  q.question.id = "t.locate";
  q.question.kind = QuestionKind::Locate;
  q.question.target = target;
  q.question.toleranceMm = toleranceMm;
  return q;
}

ResolvedQuestion nameQuestion(const std::string& target, std::vector<std::string> synonyms = {}) {
  ResolvedQuestion q;
  q.question.id = "t.name";
  q.question.kind = QuestionKind::Name;
  q.question.target = target;
  q.question.synonyms = std::move(synonyms);
  return q;
}

Answer pickAnswer(const std::string& structure, double distanceMm) {
  Answer a;
  a.pick = Pick{.structure = structure, .distanceMm = distanceMm, .pixel = std::nullopt, .view = ""};
  return a;
}

Answer textAnswer(const std::string& text) {
  Answer a;
  a.text = text;
  return a;
}

bool accepts(const ResolvedQuestion& q, const std::string& text) {
  auto g = grade(q, textAnswer(text), phantomNames());
  REQUIRE(g.has_value());
  return g->correct;
}

}  // namespace

TEST_CASE("Locate_PickOnTarget_IsCorrectWhateverTheDistance") {
  auto g = grade(locate("cochlea", 0), pickAnswer("cochlea", -1), phantomNames());
  REQUIRE(g);
  CHECK(g->correct);
  CHECK(g->score == 1.0);
}

TEST_CASE("Locate_WrongStructureWithoutTolerance_IsWrongEvenIfClose") {
  auto g = grade(locate("cochlea", 0), pickAnswer("vestibule", 0.01), phantomNames());
  REQUIRE(g);
  CHECK_FALSE(g->correct);
  CHECK(g->score == 0.0);
  CHECK(g->feedback == "Not quite: you clicked the vestibule. The cochlea was 0.01 mm away.");
}

TEST_CASE("Locate_SmallStructure_AcceptsClicksUpToAndIncludingTheTolerance") {
  const ResolvedQuestion q = locate("stapes", 0.5);
  CHECK(grade(q, pickAnswer("incus", 0.2), phantomNames())->correct);
  CHECK(grade(q, pickAnswer("", 0.5), phantomNames())->correct);             // exactly at the boundary
  CHECK(grade(q, pickAnswer("", double(0.5f)), phantomNames())->correct);    // as read from a float field
  CHECK(grade(locate("stapes", 0.3), pickAnswer("", double(0.3f)), phantomNames())->correct);
  CHECK_FALSE(grade(q, pickAnswer("", 0.5001), phantomNames())->correct);
  CHECK_FALSE(grade(q, pickAnswer("incus", std::numeric_limits<double>::quiet_NaN()), phantomNames())->correct);
  CHECK_FALSE(grade(q, pickAnswer("incus", -1), phantomNames())->correct);
  CHECK_FALSE(grade(q, pickAnswer("incus", std::numeric_limits<double>::infinity()), phantomNames())->correct);
}

TEST_CASE("Identify_ChoiceIndex_IsGradedAgainstTheKeyAndOutOfRangeIsAnError") {
  ResolvedQuestion q;
  q.question.id = "t.identify";
  q.question.kind = QuestionKind::Identify;
  q.question.target = "incus";
  q.choices = {"malleus", "incus", "stapes"};
  q.keyChoice = 1;
  Answer a;
  a.choice = 1;
  CHECK(grade(q, a, phantomNames())->correct);
  a.choice = 2;
  auto wrong = grade(q, a, phantomNames());
  CHECK_FALSE(wrong->correct);
  CHECK(wrong->feedback == "Not quite: you chose the stapes; the answer is the incus.");
  a.choice = 3;
  CHECK_FALSE(grade(q, a, phantomNames()).has_value());
  a.choice = -1;
  CHECK_FALSE(grade(q, a, phantomNames()).has_value());
}

TEST_CASE("Grade_AnswerOfTheWrongFormOrWithTwoFields_IsAnErrorNotAWrongAnswer") {
  CHECK_FALSE(grade(locate("cochlea", 0), textAnswer("cochlea"), phantomNames()).has_value());
  Answer both = textAnswer("cochlea");
  both.choice = 0;
  CHECK_FALSE(grade(nameQuestion("cochlea"), both, phantomNames()).has_value());
  CHECK_FALSE(grade(nameQuestion("cochlea"), Answer{}, phantomNames()).has_value());
}

TEST_CASE("Name_IgnoresCaseAccentsSpacingPunctuationAndArticles") {
  const ResolvedQuestion q = nameQuestion("cochlea");
  CHECK(accepts(q, "cochlea"));
  CHECK(accepts(q, "  COCHLEA "));
  CHECK(accepts(q, "Cóchlëa"));
  CHECK(accepts(q, "the cochlea."));
  CHECK(accepts(nameQuestion("lateral_semicircular_canal"), "lateral semi-circular canal"));
  CHECK(accepts(nameQuestion("lateral_semicircular_canal"), "Lateral_Semicircular_Canal"));
  CHECK_FALSE(accepts(q, ""));
  CHECK_FALSE(accepts(q, "vestibule"));
}

TEST_CASE("Name_AcceptsCatalogAndQuestionSynonyms") {
  CHECK(accepts(nameQuestion("stapes"), "stirrup"));
  CHECK(accepts(nameQuestion("lateral_semicircular_canal"), "Horizontal semicircular canal"));
  CHECK_FALSE(accepts(nameQuestion("facial_nerve"), "CN VII"));
  CHECK(accepts(nameQuestion("facial_nerve", {"CN VII"}), "cn vii"));
}

TEST_CASE("Name_ForgivesSmallTyposScaledByLength") {
  CHECK(accepts(nameQuestion("vestibule"), "vestibul"));        // 1 deletion, 9 letters
  CHECK(accepts(nameQuestion("vestibule"), "vestiblue"));       // 1 transposition
  CHECK(accepts(nameQuestion("lateral_semicircular_canal"), "lateral semicirculr canl"));  // 2 edits, long
  CHECK_FALSE(accepts(nameQuestion("vestibule"), "vstbl"));     // too many
  CHECK_FALSE(accepts(nameQuestion("incus"), "inkis"));         // 2 edits on a short name
}

TEST_CASE("Name_TypoCloserToAnotherStructure_IsNotAccepted") {
  // "posterior" is a different canal even though one letter away from a typo of nothing: the text
  // names another structure exactly.
  auto g = grade(nameQuestion("superior_semicircular_canal"), textAnswer("posterior semicircular canal"), phantomNames());
  REQUIRE(g);
  CHECK_FALSE(g->correct);

  // Classic near-miss pair: ileum vs ilium. One edit from the target but zero from the other.
  GradingContext c;
  c.names = {spellings("ileum", {"Ileum"}), spellings("ilium", {"Ilium"})};
  ResolvedQuestion ileum = nameQuestion("ileum");
  auto nearMiss = grade(ileum, textAnswer("ilium"), c);
  REQUIRE(nearMiss);
  CHECK_FALSE(nearMiss->correct);
  CHECK(nearMiss->feedback == "Not quite: \"ilium\" reads as the ilium; this is the ileum.");
  // Equally close to both: ambiguous, not accepted.
  CHECK_FALSE(grade(ileum, textAnswer("ilxum"), c)->correct);
  // Closer to the target than to the other: a forgiven typo.
  CHECK(grade(ileum, textAnswer("ileumm"), c)->correct);
}

TEST_CASE("Name_LeftRightWordOrderDoesNotMatter") {
  GradingContext c;
  c.names = {spellings("kidney_left", {"Left kidney"}), spellings("kidney_right", {"Right kidney"})};
  ResolvedQuestion q = nameQuestion("kidney_left");
  CHECK(grade(q, textAnswer("kidney left"), c)->correct);
  CHECK(grade(q, textAnswer("Kidney (L)"), c)->correct);
  CHECK(grade(q, textAnswer("left kidney"), c)->correct);
  // The other side is wrong when the question asks for the side; otherwise the name is right and
  // the feedback notes the side (quiz/sided_names.h).
  q.question.askSide = true;
  CHECK(grade(q, textAnswer("Kidney (L)"), c)->correct);
  CHECK_FALSE(grade(q, textAnswer("right kidney"), c)->correct);
  CHECK_FALSE(grade(q, textAnswer("kidney right"), c)->correct);
  q.question.askSide = false;
  const auto unasked = grade(q, textAnswer("right kidney"), c);
  CHECK(unasked->correct);
  CHECK(unasked->feedback.find("patient's left") != std::string::npos);
}

TEST_CASE("Order_FullCreditInOrderAndLcsPartialCreditOtherwise") {
  ResolvedQuestion q;
  q.question.id = "t.order";
  q.question.kind = QuestionKind::Order;
  q.question.target = "stapes";
  q.keyOrder = {"malleus", "incus", "stapes", "vestibule"};
  Answer a;
  a.order = std::vector<std::string>{"malleus", "incus", "stapes", "vestibule"};
  CHECK(grade(q, a, phantomNames())->score == 1.0);
  CHECK(grade(q, a, phantomNames())->correct);
  a.order = std::vector<std::string>{"Malleus", "anvil", "stirrup", "vestibule"};  // names and synonyms
  CHECK(grade(q, a, phantomNames())->correct);
  a.order = std::vector<std::string>{"incus", "malleus", "stapes", "vestibule"};   // LCS 3
  auto partial = grade(q, a, phantomNames());
  CHECK_FALSE(partial->correct);
  CHECK(partial->score == doctest::Approx(0.75));
  a.order = std::vector<std::string>{"vestibule", "stapes", "incus", "malleus"};   // reversed: LCS 1
  CHECK(grade(q, a, phantomNames())->score == doctest::Approx(0.25));
  a.order = std::vector<std::string>{"malleus", "incus"};                          // incomplete: 2 of 4
  CHECK(grade(q, a, phantomNames())->score == doctest::Approx(0.5));
  a.order = std::vector<std::string>{"malleus", "incus", "cochlea", "stapes", "vestibule"};  // extra: 4 of 5
  CHECK(grade(q, a, phantomNames())->score == doctest::Approx(0.8));
  a.order = std::vector<std::string>{"malleus", "nonsense"};
  CHECK_FALSE(grade(q, a, phantomNames()).has_value());
}

TEST_CASE("LongestCommonSubsequence_MatchesHandCountedCases") {
  using V = std::vector<std::string>;
  CHECK(longestCommonSubsequence(V{}, V{"a"}) == 0);
  CHECK(longestCommonSubsequence(V{"a", "b", "c", "d"}, V{"a", "c", "b", "d"}) == 3);
  CHECK(longestCommonSubsequence(V{"x", "a", "y", "b"}, V{"a", "b"}) == 2);
}

TEST_CASE("NameInSentence_LowerCasesLabelCaseButKeepsAbbreviationsAndProperNames") {
  CHECK(nameInSentence("Cochlea") == "cochlea");
  CHECK(nameInSentence("Superior semicircular canal") == "superior semicircular canal");
  CHECK(nameInSentence("Lateral semicircular canal (horizontal)") == "lateral semicircular canal (horizontal)");
  CHECK(nameInSentence("Vertebrae L1") == "vertebrae L1");
  CHECK(nameInSentence("C1") == "C1");
  CHECK(nameInSentence("CN VII") == "CN VII");
  CHECK(nameInSentence("T11 vertebra") == "T11 vertebra");
  CHECK(nameInSentence("IAC") == "IAC");
  CHECK(nameInSentence("Eustachian tube") == "Eustachian tube");
  CHECK(nameInSentence("Sylvian fissure") == "Sylvian fissure");
  CHECK(nameInSentence("Meckel's cave") == "Meckel's cave");
  CHECK(nameInSentence("Prussak\u2019s space") == "Prussak\u2019s space");
  CHECK(nameInSentence("cochlea") == "cochlea");
  CHECK(nameInSentence("") == "");
  CHECK(nameInSentence("\u00c4ußeres Ohr") == "\u00c4ußeres Ohr");  // not ASCII: kept as written
}

TEST_CASE("Feedback_NamesInsideSentencesAreLowerCaseAbbreviationsKept") {
  GradingContext c = phantomNames();
  c.names.push_back(spellings("c1", {"C1", "atlas"}));
  c.names.push_back(spellings("eustachian_tube", {"Eustachian tube"}));
  CHECK(grade(locate("cochlea", 0), pickAnswer("cochlea", 0), c)->feedback == "Correct: that is the cochlea.");
  CHECK(grade(locate("c1", 0), pickAnswer("eustachian_tube", 12.5), c)->feedback ==
        "Not quite: you clicked the Eustachian tube. The C1 was 12.5 mm away.");
  CHECK(grade(nameQuestion("facial_nerve"), textAnswer("zzzz"), c)->feedback == "Not quite: this is the facial nerve.");
  // A name alone after "Correct:" keeps its label case.
  CHECK(grade(nameQuestion("cochlea"), textAnswer("cochlea"), c)->feedback == "Correct: Cochlea.");
}
