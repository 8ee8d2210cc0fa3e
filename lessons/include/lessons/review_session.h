// A review session (ARCHITECTURE.md §5): one user's adaptive review of one course, question after
// question until nothing is due. It is the one review loop of the program: `play --review` on the
// terminal and the desktop's Review button both ask through it. Each question is chosen
// (chooseReviewQuestion), its keys resolved (quiz::resolveQuestion), shown in the course's scene,
// and each answer graded and recorded (answerReview) before the grade is returned, so the review
// queue moves.
#pragma once

#include <cstdint>
#include <optional>

#include "lessons/lesson_engine.h"

namespace at::lessons {

// A review question as the front ends ask it.
struct ReviewQuestion {
  quiz::ResolvedQuestion question;
  QuestionScene scene;  // the course's scene of the question (questionScene); the target's own
                        // default scene if the course has none
};

class ReviewSession {
 public:
  // The references must outlive the session. `userId`: a stored user (a user with no stored id
  // has been taught nothing, so nothing is due).
  ReviewSession(CurriculumRepository& curriculum, ProgressRepository& progress, quiz::KeyComputer& keys, Course course,
                std::int64_t userId, EngineOptions options = {});

  const Course& course() const { return course_; }

  // The question due now (clockNow(options)) that best fits the user, or nullopt when nothing is
  // due. It becomes the current question; a current question left unanswered is dropped.
  Result<std::optional<ReviewQuestion>> next();

  // The question next() gave last, until next() is called again.
  const std::optional<ReviewQuestion>& current() const { return current_; }

  // Grades the answer to the current question and records it (answerReview) before returning the
  // grade. Errors: no current question, one already answered, or answerReview's (nothing recorded).
  Result<quiz::Grade> answer(const quiz::Answer& answer, const RenderState& render, std::int64_t latencyMs);

  // "Show me" for the current question: its scene with the question's target highlighted in its
  // own WDT context (preset "<target>_wdt"), from the side the question was asked from.
  std::optional<QuestionScene> showMeScene() const;

  int answered() const { return answered_; }  // answers recorded in this session
  int right() const { return right_; }        // of which correct

 private:
  CurriculumRepository& curriculum_;
  ProgressRepository& progress_;
  quiz::KeyComputer& keys_;
  Course course_;
  std::int64_t userId_ = 0;
  EngineOptions options_;
  std::optional<ReviewQuestion> current_;
  bool currentAnswered_ = false;
  int answered_ = 0, right_ = 0;
};

}  // namespace at::lessons
