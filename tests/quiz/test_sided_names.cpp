// Typed names of paired structures: the side is graded apart from the name (quiz/sided_names.h).
#include <doctest/doctest.h>

#include "quiz/grading.h"
#include "quiz/sided_names.h"

using namespace at::quiz;

namespace {

// A paired structure with its counterpart, a midline one, and a near-homonym.
GradingContext skullNames() {
  GradingContext c;
  c.names = {
      {"external_acoustic_meatus_left", {"External acoustic meatus (left)", "ear canal", "external auditory meatus"},
       Side::Left, "External acoustic meatus"},
      {"external_acoustic_meatus_right", {"External acoustic meatus (right)", "ear canal", "external auditory meatus"},
       Side::Right, "External acoustic meatus"},
      {"internal_acoustic_meatus", {"Internal acoustic meatus"}, Side::None, "Internal acoustic meatus"},
      {"mastoid_air_cells_right", {"Mastoid air cells (right)"}, Side::None, ""},  // side read off the name
      {"frontal_sinus", {"Frontal sinus"}, Side::None, "Frontal sinus"},
  };
  return c;
}

ResolvedQuestion nameQuestion(const std::string& target, bool askSide) {
  ResolvedQuestion q;
  q.question.id = "t.name";
  q.question.kind = QuestionKind::Name;
  q.question.target = target;
  q.question.askSide = askSide;
  return q;
}

Grade graded(const ResolvedQuestion& q, const std::string& text) {
  Answer a;
  a.text = text;
  auto g = grade(q, a, skullNames());
  REQUIRE(g.has_value());
  return *g;
}

}  // namespace

TEST_CASE("splitSide_SideWordsAnywhere_BodyWithoutThem") {
  CHECK(splitSide("Orbit (right)").body == "orbit");
  CHECK((splitSide("Orbit (right)").side == Side::Right));
  CHECK((splitSide("left External Acoustic meatus").side == Side::Left));
  CHECK(splitSide("left External Acoustic meatus").body == "external acoustic meatus");
  CHECK(splitSide("left right orbit").conflicting);
  CHECK((splitSide("left right orbit").side == Side::None));
  CHECK(withoutSide("Orbit (right)") == "Orbit");
  CHECK(withoutSide("Right maxillary antrum") == "Maxillary antrum");
  CHECK(withoutSide("Atlas (C1)") == "Atlas (C1)");
  CHECK((sideOfName("Mastoid air cells (left)") == Side::Left));
  CHECK((sideOfName("Frontal sinus") == Side::None));
}

TEST_CASE("gradeName_SideNotAsked_SidelessNamesAndSynonymsAreRight") {
  for (const char* text : {"external acoustic meatus", "External auditory meatus", "ear canal", "the ear canal",
                           "external acustic meatus" /* typo */, "left ear canal", "External acoustic meatus (left)"}) {
    CAPTURE(text);
    const Grade g = graded(nameQuestion("external_acoustic_meatus_left", false), text);
    CHECK(g.correct);
    CHECK(g.score == 1);
    CHECK(g.feedback.find("(left)") == std::string::npos);  // the side is not presented as an answer
  }
  // The structure's own name without its side, with no synonyms at all.
  CHECK(graded(nameQuestion("mastoid_air_cells_right", false), "mastoid air cells").correct);
}

TEST_CASE("gradeName_SideNotAsked_WrongSideIsNotedButNotTheError") {
  const Grade g = graded(nameQuestion("external_acoustic_meatus_left", false), "right ear canal");
  CHECK(g.correct);
  CHECK(g.feedback.find("patient's left") != std::string::npos);
}

TEST_CASE("gradeName_WrongNames_AreWrongAndFeedbackOmitsTheUnaskedSide") {
  for (const char* text : {"internal acoustic meatus", "frontal sinus", "mastoid", "orbit", ""}) {
    CAPTURE(text);
    const Grade g = graded(nameQuestion("external_acoustic_meatus_left", false), text);
    CHECK_FALSE(g.correct);
    CHECK(g.score == 0);
    CHECK(g.feedback.find("left") == std::string::npos);
    CHECK(g.feedback.find("external acoustic meatus") != std::string::npos);
  }
}

TEST_CASE("gradeName_SideAsked_MissingSideIsPartialWithAHint_WrongSideLess") {
  const ResolvedQuestion q = nameQuestion("external_acoustic_meatus_left", true);
  const Grade right = graded(q, "left external acoustic meatus");
  CHECK(right.correct);
  const Grade missing = graded(q, "ear canal");
  CHECK_FALSE(missing.correct);
  CHECK(missing.score == 0.5);
  CHECK(missing.feedback.find("Which side?") == 0);
  CHECK(missing.feedback.find("left") != std::string::npos);
  const Grade wrongSide = graded(q, "right ear canal");
  CHECK_FALSE(wrongSide.correct);
  CHECK(wrongSide.score > 0);
  CHECK(wrongSide.score < missing.score);
  // A structure without a side cannot be asked for one: the name alone is right.
  CHECK(graded(nameQuestion("frontal_sinus", true), "frontal sinus").correct);
}
