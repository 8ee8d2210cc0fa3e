#include "lessons/review_session.h"

namespace at::lessons {

ReviewSession::ReviewSession(CurriculumRepository& curriculum, ProgressRepository& progress, quiz::KeyComputer& keys,
                             Course course, std::int64_t userId, EngineOptions options)
    : curriculum_(curriculum), progress_(progress), keys_(keys), course_(std::move(course)), userId_(userId),
      options_(std::move(options)) {}

Result<std::optional<ReviewQuestion>> ReviewSession::next() {
  current_.reset();
  currentAnswered_ = false;
  auto question = chooseReviewQuestion(curriculum_, progress_, userId_, course_.id, clockNow(options_));
  if (!question) return tl::unexpected(question.error());
  if (!*question) return std::optional<ReviewQuestion>();
  auto resolved = quiz::resolveQuestion(**question, keys_);
  if (!resolved) return tl::unexpected(resolved.error());
  ReviewQuestion asked;
  QuestionScene byDefault;
  byDefault.structure = resolved->question.target;
  asked.scene = questionScene(course_, resolved->question.id).value_or(byDefault);
  asked.question = std::move(*resolved);
  current_ = asked;
  return std::optional<ReviewQuestion>(std::move(asked));
}

Result<quiz::Grade> ReviewSession::answer(const quiz::Answer& answer, const RenderState& render, std::int64_t latencyMs) {
  if (!current_) return fail("no review question is asked");
  if (currentAnswered_) return fail("review question '" + current_->question.question.id + "' is already answered");
  ReviewAnswer review;
  review.userId = userId_;
  review.courseId = course_.id;
  review.question = current_->question.question;
  review.answer = answer;
  review.render = render;
  review.latencyMs = latencyMs;
  auto grade = answerReview(curriculum_, progress_, keys_, review, options_);
  if (!grade) return grade;
  currentAnswered_ = true;
  ++answered_;
  right_ += grade->correct ? 1 : 0;
  return grade;
}

std::optional<QuestionScene> ReviewSession::showMeScene() const {
  if (!current_) return std::nullopt;
  QuestionScene scene = current_->scene;
  const std::string& target = current_->question.question.target;
  if (!target.empty() && scene.structure != target) {
    scene.structure = target;
    scene.presetId = target + "_wdt";
  }
  return scene;
}

}  // namespace at::lessons
