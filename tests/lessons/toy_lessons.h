// FOR TESTS ONLY: the toy course of the lessons/ tests over the in-memory repositories, and the
// answers they give.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include "in_memory_repositories.h"
#include "lessons/lesson_engine.h"

namespace at::lessons::toy {

inline Step showStep(const std::string& structure) {
  Step s;
  s.kind = StepKind::Show;
  s.show = {.structure = structure,
            .presetId = structure + "_wdt",
            .view = CameraView::LateralRight,
            .title = "About " + structure,
            .text = "Text.",
            .camera = std::nullopt,
            .clip = std::nullopt};
  return s;
}

inline Step questionStep(quiz::Question q) {
  Step s;
  s.kind = StepKind::Question;
  s.question = std::move(q);
  return s;
}

inline quiz::Question nameQ(const std::string& id, const std::string& target, double difficulty = 1500) {
  quiz::Question q;
  q.id = id;
  q.kind = quiz::QuestionKind::Name;
  q.target = target;
  q.prompt = "Name the highlighted structure.";
  q.difficulty = difficulty;
  return q;
}

inline quiz::Question identifyQ(const std::string& id, const std::string& target) {
  quiz::Question q;
  q.id = id;
  q.kind = quiz::QuestionKind::Identify;
  q.target = target;
  q.prompt = "Which structure is highlighted?";
  q.distractors = 2;
  return q;
}

// Course "toy": lesson "one" (show, name cochlea, show, identify stapes, name vestibule), lesson
// "two" requiring "one" (name incus).
struct Fixture {
  test::InMemoryCurriculum curriculum;
  test::InMemoryProgress progress;
  test::TableKeyComputer keys;
  UnixSeconds clock = 1'000'000;

  Fixture() {
    Course c;
    c.id = "toy";
    c.title = "Toy";
    c.datasetId = "phantom";
    c.synonyms["stapes"] = {"stirrup"};
    Lesson one;
    one.id = "one";
    one.courseId = "toy";
    one.title = "Lesson one";
    one.steps = {showStep("cochlea"), questionStep(nameQ("one.q1", "cochlea", 1400)), showStep("stapes"),
                 questionStep(identifyQ("one.q2", "stapes")), questionStep(nameQ("one.q3", "vestibule", 1600))};
    Lesson two;
    two.id = "two";
    two.courseId = "toy";
    two.title = "Lesson two";
    two.prerequisites = {"one"};
    two.steps = {questionStep(nameQ("two.q1", "incus"))};
    c.lessons = {one, two};
    curriculum.courseList = {c};
    const auto structure = [](std::uint16_t label, const char* id, const char* name) {
      Structure s;
      s.label = label;
      s.id = id;
      s.displayName = name;
      return s;
    };
    curriculum.datasets["phantom"] = {structure(1, "cochlea", "Cochlea"), structure(2, "vestibule", "Vestibule"),
                                      structure(3, "stapes", "Stapes"), structure(4, "incus", "Incus"),
                                      structure(5, "malleus", "Malleus")};
    keys.structureIds = {"cochlea", "vestibule", "stapes", "incus", "malleus"};
    keys.distances["stapes"] = {{"stapes", 0}, {"incus", 0.1}, {"malleus", 0.9}, {"vestibule", 0.4}, {"cochlea", 3}};
  }

  EngineOptions options() {
    EngineOptions o;
    o.clock = [this] { return clock; };
    return o;
  }
};

inline quiz::Answer text(const std::string& t) {
  quiz::Answer a;
  a.text = t;
  return a;
}

inline quiz::Answer choice(int c) {
  quiz::Answer a;
  a.choice = c;
  return a;
}

inline int indexOf(const std::vector<std::string>& v, const std::string& x) {
  return int(std::find(v.begin(), v.end(), x) - v.begin());
}


}  // namespace at::lessons::toy
