// LessonController: going back a step, "show me" after an answer, and the review of a finished
// lesson (lesson_controller.h).
#include "lesson_player/lesson_controller.h"

namespace at::app {

using json = nlohmann::json;

Status LessonController::back() {
  if (!engine_ || !step_) return fail("no lesson is running");
  if (auto st = engine_->back(); !st) return st;
  return showCurrent();
}

Status LessonController::showMe(bool onSlice) {
  if (!asked_ || !asked_->grade) return fail("answer the question first; then \"show me\" shows the answer");
  const std::string& questionId = asked_->question.question.id;
  std::optional<lessons::QuestionScene> scene;
  if (!asked_->review && engine_ && step_) {
    scene = lessons::showMeScene(engine_->lesson().steps[std::size_t(step_->index)]);
  } else if (asked_->review && reviewSession_) {
    scene = reviewSession_->showMeScene();
  }
  if (!scene) return fail("question '" + questionId + "' has no view to show its answer in");
  show_({scene->structure, scene->presetId, scene->view, scene->camera, scene->clip, {}, onSlice});
  events_({{"event", "show_me"}, {"question", questionId}, {"structure", scene->structure},
           {"preset", scene->presetId}, {"view", lessons::toString(scene->view)}, {"slice", onSlice}});
  return {};
}

Status LessonController::showReviewItem(int index, bool onSlice) {
  if (index < 0 || index >= int(review_.size())) {
    return fail("the lesson review has items 0.." + std::to_string(int(review_.size()) - 1) + ", not " +
                std::to_string(index));
  }
  const lessons::QuestionOutcome& o = review_[std::size_t(index)];
  show_({o.scene.structure, o.scene.presetId, o.scene.view, o.scene.camera, o.scene.clip, {}, onSlice});
  events_({{"event", "review_item"}, {"index", index}, {"question", o.questionId}, {"structure", o.scene.structure},
           {"slice", onSlice},
           {"correct", o.grade && o.grade->correct}, {"your_answer", o.yourAnswer}, {"right_answer", o.rightAnswer}});
  return {};
}

}  // namespace at::app
