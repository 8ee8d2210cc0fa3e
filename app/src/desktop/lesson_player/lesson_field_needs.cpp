#include "lesson_player/lesson_field_needs.h"

#include "lessons/lesson_engine.h"
#include "quiz/question.h"

namespace at::app {

namespace {

using Kind = LessonFieldNeed::Kind;

void addView(std::vector<LessonFieldNeed>& out, const std::vector<lessons::Step>& steps, int index) {
  const lessons::Step& step = steps[std::size_t(index)];
  if (step.kind == lessons::StepKind::Show) out.push_back({Kind::View, index, step.show.structure, step.show.presetId});
  if (step.kind == lessons::StepKind::Question) {
    const lessons::QuestionScene scene = lessons::sceneFor(step);
    out.push_back({Kind::View, index, scene.structure, scene.presetId});
  }
}

// What a question's answer may need: the locate target's answer key, the show-me scene's field.
void addAfterAnswer(std::vector<LessonFieldNeed>& out, const std::vector<lessons::Step>& steps, int index) {
  const lessons::Step& step = steps[std::size_t(index)];
  if (step.kind != lessons::StepKind::Question) return;
  if (step.question.kind == quiz::QuestionKind::Locate && !step.question.target.empty())
    out.push_back({Kind::AnswerKey, index, step.question.target, ""});
  const lessons::QuestionScene showMe = lessons::showMeScene(step);
  out.push_back({Kind::ShowMe, index, showMe.structure, showMe.presetId});
}

}  // namespace

std::vector<LessonFieldNeed> lessonFieldNeeds(const std::vector<lessons::Step>& steps, int current,
                                              const std::vector<int>& upcoming) {
  std::vector<LessonFieldNeed> out;
  const auto valid = [&](int i) { return i >= 0 && std::size_t(i) < steps.size(); };
  if (valid(current)) addView(out, steps, current);
  if (!upcoming.empty() && valid(upcoming.front())) addView(out, steps, upcoming.front());
  if (valid(current)) addAfterAnswer(out, steps, current);
  for (std::size_t i = 0; i < upcoming.size(); ++i) {
    if (!valid(upcoming[i])) continue;
    if (i > 0) addView(out, steps, upcoming[i]);
    addAfterAnswer(out, steps, upcoming[i]);
  }
  return out;
}

}  // namespace at::app
