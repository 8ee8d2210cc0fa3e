// lessons::ReviewSession: the one review loop `play --review` and the desktop's Review button run.
#include <doctest/doctest.h>

#include <set>

#include "lessons/review_session.h"
#include "toy_lessons.h"

using namespace at;
using namespace at::lessons;
using namespace at::lessons::toy;

namespace {

// Lesson one of the toy course answered throughout (right) by user 1, then a month passes: its
// three structures are due.
void teachLessonOne(Fixture& f) {
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "one"));
  while (!engine.atEnd()) {
    auto step = engine.current();
    REQUIRE(step);
    if (step->kind == StepKind::Question) {
      if (step->questionKind == quiz::QuestionKind::Identify)
        REQUIRE(engine.answer(choice(indexOf(step->choiceIds, step->structure)), {}, 0));
      else
        REQUIRE(engine.answer(text(step->structure), {}, 0));
    }
    REQUIRE(engine.next());
  }
  REQUIRE(engine.finish());
  f.clock += 30 * 86400;
}

quiz::Answer rightAnswer(const quiz::ResolvedQuestion& q) {
  return q.question.kind == quiz::QuestionKind::Identify ? choice(q.keyChoice) : text(q.question.target);
}

quiz::Answer wrongAnswer(const quiz::ResolvedQuestion& q) {
  if (q.question.kind == quiz::QuestionKind::Identify) return choice((q.keyChoice + 1) % int(q.choices.size()));
  return text(q.question.target == "malleus" ? "incus" : "malleus");
}

const RenderState kRender{"stapes_wdt", "wdt", 0.4, 1.2, 0.8};

}  // namespace

TEST_CASE("ReviewSession asks what is due until nothing is, recording each answer and counting them") {
  Fixture f;
  teachLessonOne(f);
  const std::size_t recordsBefore = f.progress.reviewList.size();
  ReviewSession review(f.curriculum, f.progress, f.keys, *f.curriculum.course("toy"), 1, f.options());
  std::set<std::string> asked;
  int wrongGiven = 0;
  for (int i = 0; i < 20; ++i) {
    auto next = review.next();
    REQUIRE(next);
    if (!next->has_value()) break;
    const ReviewQuestion& q = **next;
    CHECK(q.question.question.id.rfind("one.", 0) == 0);  // only what lesson one taught
    CHECK(review.current().has_value());
    // The course's scene of the question, as the lesson asked it.
    const auto scene = questionScene(*f.curriculum.course("toy"), q.question.question.id);
    REQUIRE(scene);
    CHECK(q.scene.structure == scene->structure);
    CHECK((q.scene.view == scene->view));
    // The first answer to the first question is wrong: it counts as answered, not right, and
    // sends the structure back to relearning (so it comes back later in this session).
    const bool wrong = i == 0;
    auto grade = review.answer(wrong ? wrongAnswer(q.question) : rightAnswer(q.question), kRender, 1000);
    REQUIRE_MESSAGE(grade, (grade ? "" : grade.error().message));
    CHECK(grade->correct == !wrong);
    wrongGiven += wrong ? 1 : 0;
    asked.insert(q.question.question.target);
    // One answer per question.
    CHECK_FALSE(review.answer(rightAnswer(q.question), kRender, 1000));
    if (!wrong) f.clock += 86400 * 2;  // relearning steps pass before the wrong one comes back
  }
  CHECK(asked == std::set<std::string>{"cochlea", "stapes", "vestibule"});
  CHECK(review.answered() >= 3);
  CHECK(review.right() == review.answered() - wrongGiven);
  CHECK(f.progress.reviewList.size() == recordsBefore + std::size_t(review.answered()));
  CHECK_FALSE(review.current().has_value());  // next() said nothing is due
  CHECK(reviewQueue(f.curriculum, f.progress, 1, "toy", f.clock)->empty());
}

TEST_CASE("ReviewSession: nothing taught means nothing due, and no question means no answer") {
  Fixture f;
  ReviewSession review(f.curriculum, f.progress, f.keys, *f.curriculum.course("toy"), 1, f.options());
  auto next = review.next();
  REQUIRE(next);
  CHECK_FALSE(next->has_value());
  CHECK_FALSE(review.answer(text("cochlea"), kRender, 0));
  CHECK_FALSE(review.showMeScene().has_value());
  CHECK(review.answered() == 0);
  CHECK(f.progress.reviewList.empty());
}

TEST_CASE("ReviewSession: a failed answer records nothing, counts nothing and may be given again") {
  Fixture f;
  teachLessonOne(f);
  const std::size_t recordsBefore = f.progress.reviewList.size();
  ReviewSession review(f.curriculum, f.progress, f.keys, *f.curriculum.course("toy"), 1, f.options());
  auto next = review.next();
  REQUIRE(next);
  REQUIRE(next->has_value());
  const quiz::ResolvedQuestion q = (*next)->question;
  f.progress.failNextRecord = true;
  CHECK_FALSE(review.answer(rightAnswer(q), kRender, 0));
  CHECK(review.answered() == 0);
  CHECK(f.progress.reviewList.size() == recordsBefore);
  auto again = review.answer(rightAnswer(q), kRender, 0);
  REQUIRE(again);
  CHECK(again->correct);
  CHECK(review.answered() == 1);
  CHECK(review.right() == 1);
  CHECK(f.progress.reviewList.size() == recordsBefore + 1);
}

TEST_CASE("ReviewSession: show me highlights the question's target in its own WDT context from the asked side") {
  Fixture f;
  teachLessonOne(f);
  ReviewSession review(f.curriculum, f.progress, f.keys, *f.curriculum.course("toy"), 1, f.options());
  for (int i = 0; i < 10; ++i) {
    auto next = review.next();
    REQUIRE(next);
    if (!next->has_value()) break;
    const ReviewQuestion q = **next;
    const auto shown = review.showMeScene();
    REQUIRE(shown);
    CHECK(shown->structure == q.question.question.target);
    CHECK((shown->view == q.scene.view));
    if (q.scene.structure != q.question.question.target) CHECK(shown->presetId == q.question.question.target + "_wdt");
    else CHECK(shown->presetId == q.scene.presetId);
    REQUIRE(review.answer(rightAnswer(q.question), kRender, 0));
  }
}
