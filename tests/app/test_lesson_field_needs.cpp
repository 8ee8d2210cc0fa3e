// What the desktop prefetches while a student reads a lesson step (lessonFieldNeeds): for every
// step of every lesson of the shipped courses, the list starts with the step's own view and the
// next step's, holds every later step's view in order, a locate question's answer key and every
// question's show-me field, and nothing for steps already behind the student.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "lesson_player/lesson_field_needs.h"
#include "lessons/course_json.h"
#include "lessons/lesson_engine.h"
#include "test_support.h"

using namespace at;
using Kind = app::LessonFieldNeed::Kind;

namespace {

std::string viewStructureOf(const lessons::Step& step) {
  if (step.kind == lessons::StepKind::Show) return step.show.structure;
  if (step.kind == lessons::StepKind::Question) return lessons::sceneFor(step).structure;
  return "";
}

}  // namespace

TEST_CASE("a lesson step's prefetch list: its own view, the next step's, then every later need in order") {
  int checkedSteps = 0;
  for (const char* file : {"temporal_bone.json", "skull.json"}) {
    auto course = lessons::loadCourseJson(test::sourceDir() / "data" / "courses" / file);
    REQUIRE_MESSAGE(course, file);
    for (const lessons::Lesson& lesson : course->lessons) {
      const auto& steps = lesson.steps;
      for (int current = 0; current < int(steps.size()); ++current) {
        INFO(lesson.id << " step " << current);
        std::vector<int> upcoming;
        for (int i = current + 1; i < int(steps.size()); ++i) upcoming.push_back(i);
        const auto needs = app::lessonFieldNeeds(steps, current, upcoming);
        REQUIRE(!needs.empty());
        CHECK(needs[0].kind == Kind::View);
        CHECK(needs[0].step == current);
        CHECK(needs[0].structure == viewStructureOf(steps[std::size_t(current)]));
        if (!upcoming.empty()) {
          REQUIRE(needs.size() >= 2);
          CHECK(needs[1].kind == Kind::View);
          CHECK(needs[1].step == current + 1);
        }
        // Never a step behind the student; views in step order; each upcoming step's view there.
        int lastView = -1;
        for (const auto& n : needs) {
          CHECK(n.step >= current);
          CHECK_FALSE(n.structure.empty());
          if (n.kind == Kind::View) {
            CHECK(n.step > lastView);
            lastView = n.step;
          }
        }
        for (int i : upcoming)
          CHECK(std::any_of(needs.begin(), needs.end(), [&](const auto& n) { return n.kind == Kind::View && n.step == i; }));
        // After an answer: a locate question's answer key of its target, every question's show-me.
        for (int i = current; i < int(steps.size()); ++i) {
          const lessons::Step& s = steps[std::size_t(i)];
          const auto has = [&](Kind k, const std::string& structure) {
            return std::any_of(needs.begin(), needs.end(),
                               [&](const auto& n) { return n.kind == k && n.step == i && n.structure == structure; });
          };
          if (s.kind != lessons::StepKind::Question) {
            CHECK_FALSE(std::any_of(needs.begin(), needs.end(), [&](const auto& n) { return n.step == i && n.kind != Kind::View; }));
            continue;
          }
          CHECK(has(Kind::ShowMe, lessons::showMeScene(s).structure));
          CHECK(has(Kind::AnswerKey, s.question.target) == (s.question.kind == quiz::QuestionKind::Locate));
        }
        ++checkedSteps;
      }
    }
  }
  std::printf("prefetch lists checked for %d lesson steps\n", checkedSteps);
  CHECK(checkedSteps > 20);
}
