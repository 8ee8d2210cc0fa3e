#include <doctest/doctest.h>

#include <set>

#include "in_memory_repositories.h"
#include "lessons/lesson_engine.h"
#include "lessons/scheduling.h"
#include "quiz/elo.h"
#include "toy_lessons.h"

using namespace at;
using namespace at::lessons;
using namespace at::lessons::toy;

TEST_CASE("LessonEngine_RunsALessonStartToFinishRecordingEveryAnswer") {
  Fixture f;
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "one"));
  CHECK_FALSE(engine.resumed());

  auto step = engine.current();
  REQUIRE(step);
  CHECK((step->kind == StepKind::Show));
  CHECK(step->position == 1);
  CHECK(step->count == 5);
  CHECK(step->structureName == "Cochlea");
  CHECK_FALSE(engine.answer(text("cochlea"), {}, 10));  // a show step takes no answer
  REQUIRE(engine.next());

  step = engine.current();
  CHECK((step->kind == StepKind::Question));
  CHECK_FALSE(engine.next());  // unanswered question: cannot move on
  auto g = engine.answer(text("Cochlea"), RenderState{"cochlea_wdt", "wdt", 0.4, 1.6, 1.0}, 1234);
  REQUIRE(g);
  CHECK(g->correct);
  // Recorded before answer() returned: response, progress, Elo.
  REQUIRE(f.progress.responseList.size() == 1);
  const Response& r = f.progress.responseList[0];
  CHECK(r.questionId == "one.q1");
  CHECK(r.stepIndex == 1);
  CHECK(r.latencyMs == 1234);
  CHECK(r.render.presetId == "cochlea_wdt");
  CHECK(r.render.t == 0.4);
  CHECK(*r.answer.text == "Cochlea");
  // Right within 8 s on a name question: Easy, so the cochlea skips the learning steps.
  const Fsrs fsrs;
  const MemoryState easy = fsrs.review(MemoryState{}, Rating::Easy, f.clock);
  const StructureProgress& cochlea = f.progress.progressMap[{1, "cochlea"}];
  CHECK((cochlea.memory.phase == MemoryPhase::Review));
  CHECK(cochlea.memory.stability == doctest::Approx(easy.stability));
  CHECK(cochlea.memory.due == easy.due);
  REQUIRE(f.progress.log.size() == 1);
  CHECK((f.progress.log[0].rating == Rating::Easy));
  CHECK((f.progress.log[0].phaseBefore == MemoryPhase::New));
  CHECK(f.progress.log[0].questionId == "one.q1");
  const auto elo = quiz::updateElo(1500, 1400, 1.0);
  CHECK(f.progress.abilities[1] == doctest::Approx(elo.ability));
  CHECK(f.progress.difficulties["one.q1"] == doctest::Approx(elo.difficulty));
  CHECK_FALSE(engine.answer(text("cochlea"), {}, 10));  // answered once only
  CHECK(engine.current()->feedback.has_value());
  REQUIRE(engine.next());
  REQUIRE(engine.next());  // show stapes

  step = engine.current();
  REQUIRE((step->questionKind == quiz::QuestionKind::Identify));
  CHECK(step->choiceIds.size() == 3);  // stapes + 2 nearest (incus, vestibule)
  CHECK(indexOf(step->choiceIds, "malleus") == 3);
  const int wrong = indexOf(step->choiceIds, "incus");
  g = engine.answer(choice(wrong), {}, 500);
  REQUIRE(g);
  CHECK_FALSE(g->correct);
  // Wrong: Again, the first learning step (1 minute).
  CHECK((f.progress.progressMap[{1, "stapes"}].memory.phase == MemoryPhase::Learning));
  CHECK(f.progress.progressMap[{1, "stapes"}].memory.due == f.clock + 60);
  CHECK((f.progress.log.back().rating == Rating::Again));
  REQUIRE(engine.next());

  CHECK_FALSE(engine.finish());  // one question left
  REQUIRE(engine.answer(text("vestibul"), {}, 50));
  REQUIRE(engine.next());
  CHECK(engine.atEnd());
  CHECK_FALSE(engine.current());
  auto score = engine.finish();
  REQUIRE(score);
  CHECK(*score == doctest::Approx(2.0 / 3.0));
  CHECK(f.progress.attemptList[0].finishedAt.has_value());
  CHECK(f.progress.attemptList[0].score == doctest::Approx(2.0 / 3.0));
  CHECK(f.progress.responseList.size() == 3);
}

TEST_CASE("LessonEngine_ResumesAPartialAttemptAtTheFirstUnansweredStep") {
  Fixture f;
  {
    LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
    REQUIRE(engine.start(1, "one"));
    REQUIRE(engine.next());
    REQUIRE(engine.answer(text("cochlea"), {}, 10));
    // the process dies here, after the answer, before next()
  }
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "one"));
  CHECK(engine.resumed());
  CHECK(f.progress.attemptList.size() == 1);
  auto step = engine.current();
  REQUIRE(step);
  CHECK(step->index == 2);  // the show step after the answered question
  REQUIRE(engine.next());
  REQUIRE(engine.current()->questionId == "one.q2");
  const auto stapes = indexOf(engine.current()->choiceIds, "stapes");
  REQUIRE(engine.answer(choice(stapes), {}, 10)->correct);
  {
    // die again after answering q2 and moving on
    REQUIRE(engine.next());
  }
  LessonEngine third(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(third.start(1, "one"));
  CHECK(third.current()->questionId == "one.q3");
  // The choices shown are stable across resumes (same order as before).
  CHECK(f.progress.responseList.size() == 2);
  REQUIRE(third.answer(text("vestibule"), {}, 10));
  REQUIRE(third.next());
  CHECK(*third.finish() == doctest::Approx(1.0));
}

TEST_CASE("LessonEngine_PrerequisitesMustBeFinishedAndTheErrorNamesThem") {
  Fixture f;
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  auto blocked = engine.start(1, "two");
  REQUIRE_FALSE(blocked);
  CHECK(blocked.error().message == "lesson 'two' (Lesson two) needs 'one' (Lesson one) finished first");
  CHECK(f.progress.attemptList.empty());

  REQUIRE(engine.start(1, "one"));
  while (!engine.atEnd()) {
    auto step = engine.current();
    if (step->kind == StepKind::Question) {
      if (step->questionKind == quiz::QuestionKind::Identify) REQUIRE(engine.answer(choice(0), {}, 1));
      else REQUIRE(engine.answer(text(step->structure), {}, 1));
    }
    REQUIRE(engine.next());
  }
  REQUIRE(engine.finish());
  CHECK(engine.start(1, "two"));
  // Another user has not finished lesson one.
  CHECK_FALSE(engine.start(2, "two"));
  CHECK_FALSE(engine.start(1, "three"));
}

TEST_CASE("LessonEngine_QuizOnlyModeSkipsShowStepsAndHidesNames") {
  Fixture f;
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "one", LessonMode::QuizOnly));
  auto step = engine.current();
  REQUIRE(step);
  CHECK((step->kind == StepKind::Question));
  CHECK(step->count == 3);
  CHECK_FALSE(step->labelsVisible);
  CHECK(step->structureName.empty());
  // Resuming keeps the stored mode whatever is asked.
  REQUIRE(engine.answer(text("cochlea"), {}, 1));
  LessonEngine again(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(again.start(1, "one", LessonMode::Guided));
  CHECK((again.attempt().mode == LessonMode::QuizOnly));
  CHECK(again.current()->questionId == "one.q2");
}

TEST_CASE("LessonEngine_StorageFailureMeansTheAnswerDidNotCount") {
  Fixture f;
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "one"));
  REQUIRE(engine.next());
  f.progress.failNextRecord = true;
  auto g = engine.answer(text("cochlea"), {}, 1);
  REQUIRE_FALSE(g);
  CHECK(g.error().message.find("disk full") != std::string::npos);
  CHECK_FALSE(engine.next());                       // still unanswered
  CHECK(engine.answer(text("cochlea"), {}, 1));     // can be given again
  CHECK(f.progress.responseList.size() == 1);
}

TEST_CASE("LessonEngine_MalformedAnswerIsReportedAndNothingRecorded") {
  Fixture f;
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "one"));
  REQUIRE(engine.next());
  CHECK_FALSE(engine.answer(choice(0), {}, 1));  // a name question needs text
  CHECK(f.progress.responseList.empty());
}

TEST_CASE("ReviewQueue_AndAdaptiveReview_FollowDueTimesAndAbility") {
  Fixture f;
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "one"));
  REQUIRE(engine.next());
  REQUIRE(engine.answer(text("cochlea"), {}, 1));   // right and fast: Easy, due in 8 days
  REQUIRE(engine.next());
  REQUIRE(engine.next());
  REQUIRE(engine.answer(choice(indexOf(engine.current()->choiceIds, "incus")), {}, 1));  // wrong: 1 min
  auto queue = reviewQueue(f.curriculum, f.progress, 1, "toy", f.clock + 3600);
  REQUIRE(queue);
  REQUIRE(queue->size() == 1);
  CHECK(queue->front().structureId == "stapes");
  CHECK(reviewQueue(f.curriculum, f.progress, 1, "toy", f.clock + 7 * 86400)->size() == 1);
  queue = reviewQueue(f.curriculum, f.progress, 1, "toy", f.clock + 8 * 86400);
  REQUIRE(queue->size() == 2);
  CHECK(queue->front().structureId == "stapes");  // due earlier
  CHECK(queue->back().structureId == "cochlea");

  // 1 hour later only the stapes is due: vestibule (taught in lesson one, never answered) and
  // incus (lesson two, not started) are not reviewed, and cochlea is not due yet.
  auto chosen = chooseReviewQuestion(f.curriculum, f.progress, 1, "toy", f.clock + 3600);
  REQUIRE(chosen);
  REQUIRE(chosen->has_value());
  CHECK((*chosen)->id == "one.q2");
  // 8 days later both are due: the choice is the due question whose expected success is nearest
  // 0.7 (recomputed here).
  chosen = chooseReviewQuestion(f.curriculum, f.progress, 1, "toy", f.clock + 8 * 86400);
  REQUIRE(chosen->has_value());
  const double ability = f.progress.abilities[1];
  double bestGap = 2;
  std::string best;
  for (const auto& [id, diff] : std::vector<std::pair<std::string, double>>{
           {"one.q1", f.progress.difficulties["one.q1"]}, {"one.q2", f.progress.difficulties["one.q2"]}}) {
    const double gap = std::abs(quiz::expectedScore(ability, diff) - 0.7);
    if (gap < bestGap) bestGap = gap, best = id;
  }
  CHECK((*chosen)->id == best);
}

// ---------------------------------------------------------------------------------------------
// Review answers (answerReview): graded like lesson answers, recorded, and moving the queue.

namespace {

// The stapes identify question of the fixture resolved as the app resolves it before asking.
quiz::ResolvedQuestion resolvedStapes(Fixture& f) {
  auto q = f.curriculum.question("one.q2");
  REQUIRE(q);
  auto resolved = quiz::resolveQuestion(*q, f.keys);
  REQUIRE_MESSAGE(resolved, (resolved ? "" : resolved.error().message));
  return *resolved;
}

ReviewAnswer reviewOf(const quiz::Question& question, quiz::Answer answer) {
  ReviewAnswer r;
  r.userId = 1;
  r.courseId = "toy";
  r.question = question;
  r.answer = std::move(answer);
  r.render = {"stapes_wdt", "wdt", 0.4, 1.2, 0.8};
  r.latencyMs = 2345;
  return r;
}

bool inQueue(Fixture& f, const std::string& structure, UnixSeconds at) {
  auto queue = reviewQueue(f.curriculum, f.progress, 1, "toy", at);
  REQUIRE(queue);
  return std::any_of(queue->begin(), queue->end(),
                     [&](const StructureProgress& p) { return p.structureId == structure; });
}

}  // namespace

TEST_CASE("AnswerReview_RightAnswerReschedulesTheStructureLaterAndOutOfTheQueue") {
  Fixture f;
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "one"));
  REQUIRE(engine.next());
  REQUIRE(engine.answer(text("cochlea"), {}, 1));
  REQUIRE(engine.next());
  REQUIRE(engine.next());
  REQUIRE(engine.answer(choice(indexOf(engine.current()->choiceIds, "incus")), {}, 1));  // wrong: Again
  const UnixSeconds wrongAt = f.clock;
  f.clock += 3600;
  REQUIRE(inQueue(f, "stapes", f.clock));

  const quiz::ResolvedQuestion q = resolvedStapes(f);
  const double abilityBefore = f.progress.abilities.at(1), difficultyBefore = f.progress.difficulties.at("one.q2");
  auto grade = answerReview(f.curriculum, f.progress, f.keys,
                            reviewOf(q.question, choice(indexOf(q.choices, "stapes"))), f.options());
  REQUIRE_MESSAGE(grade, (grade ? "" : grade.error().message));
  CHECK(grade->correct);
  CHECK(grade->score == doctest::Approx(1.0));

  // Again, then right within 4 s an hour later (Easy, the same day): graduates to Review with the
  // FSRS same-day stability; no longer in the queue now, back when its interval has passed.
  const Fsrs fsrs;
  const MemoryState expected = fsrs.review(fsrs.review(MemoryState{}, Rating::Again, wrongAt), Rating::Easy, f.clock);
  const StructureProgress& p = f.progress.progressMap.at({1, "stapes"});
  CHECK((p.memory.phase == MemoryPhase::Review));
  CHECK(p.memory.stability == doctest::Approx(expected.stability));
  CHECK(p.memory.due == expected.due);
  CHECK(p.memory.due >= f.clock + 86400);
  CHECK(p.answered == 2);
  CHECK(p.correct == 1);
  CHECK(p.memory.lastReview == f.clock);
  CHECK_FALSE(inQueue(f, "stapes", f.clock));
  CHECK(inQueue(f, "stapes", p.memory.due));
  REQUIRE(f.progress.log.size() == 3);
  CHECK((f.progress.log.back().source == AnswerSource::Review));
  CHECK((f.progress.log.back().phaseBefore == MemoryPhase::Learning));
  CHECK(f.progress.log.back().elapsedDays == 0);

  // Elo moved from the values before the review, as for a lesson answer.
  const quiz::EloUpdate elo = quiz::updateElo(abilityBefore, difficultyBefore, 1.0);
  CHECK(f.progress.abilities.at(1) == doctest::Approx(elo.ability));
  CHECK(f.progress.difficulties.at("one.q2") == doctest::Approx(elo.difficulty));
  CHECK(f.progress.abilities.at(1) > abilityBefore);

  // The review response is stored on its own (no attempt), with what was on screen.
  CHECK(f.progress.responseList.size() == 2);
  REQUIRE(f.progress.reviewList.size() == 1);
  const ReviewResponse& r = f.progress.reviewList[0];
  CHECK(r.userId == 1);
  CHECK(r.questionId == "one.q2");
  CHECK(r.structureId == "stapes");
  CHECK(r.correct);
  CHECK(r.latencyMs == 2345);
  CHECK(r.render.presetId == "stapes_wdt");
  CHECK(r.answeredAt == f.clock);
  CHECK(r.answer.choice == std::optional<int>(indexOf(q.choices, "stapes")));
}

TEST_CASE("AnswerReview_WrongAnswerSendsTheStructureToRelearning") {
  Fixture f;
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "one"));
  REQUIRE(engine.next());
  REQUIRE(engine.answer(text("cochlea"), {}, 1));  // right and fast: Easy, due in 8 days
  const StructureProgress before = f.progress.progressMap.at({1, "cochlea"});
  f.clock += 9 * 86400;
  REQUIRE(inQueue(f, "cochlea", f.clock));

  auto q = f.curriculum.question("one.q1");
  REQUIRE(q);
  auto grade = answerReview(f.curriculum, f.progress, f.keys, reviewOf(*q, text("malleus")), f.options());
  REQUIRE(grade);
  CHECK_FALSE(grade->correct);
  const StructureProgress& p = f.progress.progressMap.at({1, "cochlea"});
  CHECK((p.memory.phase == MemoryPhase::Relearning));
  CHECK(p.memory.lapses == 1);
  CHECK(p.memory.stability < before.memory.stability);
  CHECK(p.memory.due == f.clock + 600);  // the relearning step
  CHECK(p.answered == 2);
  CHECK(p.correct == 1);
  CHECK_FALSE(inQueue(f, "cochlea", f.clock));
  CHECK(inQueue(f, "cochlea", f.clock + 600));
  CHECK(f.progress.log.back().elapsedDays == 9);
  REQUIRE(f.progress.reviewList.size() == 1);
  CHECK_FALSE(f.progress.reviewList[0].correct);
}

TEST_CASE("AnswerReview_GradesNamesWithTheCourseSynonymsAsLessonsDo") {
  Fixture f;
  const quiz::GradingContext context = gradingContext(f.curriculum.datasets["phantom"], f.curriculum.courseList[0]);
  const auto stapes = std::find_if(context.names.begin(), context.names.end(),
                                   [](const quiz::NameEntry& e) { return e.structureId == "stapes"; });
  REQUIRE(stapes != context.names.end());
  CHECK(stapes->names == std::vector<std::string>{"Stapes", "stapes", "stirrup"});
  CHECK(context.displayName("stapes") == "Stapes");

  // A review name question on the stapes, answered with the course's synonym.
  f.curriculum.courseList[0].lessons[1].steps.push_back(questionStep(nameQ("two.q2", "stapes")));
  auto q = f.curriculum.question("two.q2");
  REQUIRE(q);
  auto grade = answerReview(f.curriculum, f.progress, f.keys, reviewOf(*q, text("Stirrup")), f.options());
  REQUIRE_MESSAGE(grade, (grade ? "" : grade.error().message));
  CHECK(grade->correct);
  // Another structure's name is not accepted.
  CHECK_FALSE(answerReview(f.curriculum, f.progress, f.keys, reviewOf(*q, text("incus")), f.options())->correct);
  // A first review answer starts the structure's progress as a first lesson answer would; the
  // second (wrong) one sent it back to the first learning step.
  CHECK(f.progress.reviewList.size() == 2);
  CHECK(f.progress.progressMap.at({1, "stapes"}).memory.step == 0);
  CHECK((f.progress.log.back().rating == Rating::Again));
  CHECK(f.progress.progressMap.at({1, "stapes"}).answered == 2);
}

TEST_CASE("AnswerReview_StorageFailureOrBadInputRecordsNothing") {
  Fixture f;
  auto q = f.curriculum.question("one.q1");
  REQUIRE(q);

  f.progress.failNextRecord = true;
  auto failed = answerReview(f.curriculum, f.progress, f.keys, reviewOf(*q, text("cochlea")), f.options());
  REQUIRE_FALSE(failed);
  CHECK(failed.error().message.find("disk full") != std::string::npos);
  CHECK(f.progress.reviewList.empty());
  CHECK(f.progress.progressMap.empty());
  CHECK(f.progress.abilities.empty());
  CHECK(f.progress.difficulties.empty());

  // An answer that does not fit the question (a choice for a name question).
  CHECK_FALSE(answerReview(f.curriculum, f.progress, f.keys, reviewOf(*q, choice(0)), f.options()));
  // A question of another course, and an unknown course.
  quiz::Question stranger = *q;
  stranger.id = "elsewhere.q1";
  auto foreign = answerReview(f.curriculum, f.progress, f.keys, reviewOf(stranger, text("cochlea")), f.options());
  REQUIRE_FALSE(foreign);
  CHECK(foreign.error().message.find("elsewhere.q1") != std::string::npos);
  ReviewAnswer unknownCourse = reviewOf(*q, text("cochlea"));
  unknownCourse.courseId = "nope";
  CHECK_FALSE(answerReview(f.curriculum, f.progress, f.keys, unknownCourse, f.options()));
  CHECK(f.progress.reviewList.empty());
  CHECK(f.progress.progressMap.empty());

  // After the failure the same answer can be given and counts.
  CHECK(answerReview(f.curriculum, f.progress, f.keys, reviewOf(*q, text("cochlea")), f.options()));
  CHECK(f.progress.reviewList.size() == 1);
}

TEST_CASE("Review_AsksOnlyAboutTaughtStructures_NotLockedOrUnstartedLessons") {
  Fixture f;
  // Nothing taught: nothing to review, even though every structure is "never answered".
  CHECK(taughtStructures(f.curriculum, f.progress, 1, "toy")->empty());
  CHECK_FALSE(chooseReviewQuestion(f.curriculum, f.progress, 1, "toy", f.clock)->has_value());

  // The user answers about the incus elsewhere (another course's lesson, an exam): a memory state,
  // but lesson two, whose question asks about it, is not started, so it is not taught here.
  StructureProgress incus{.userId = 1, .structureId = "incus", .memory = {}};
  incus = scheduleAnswer(incus, Rating::Good, true, f.clock, Fsrs());
  f.progress.progressMap[{1, "incus"}] = incus;
  CHECK(reviewQueue(f.curriculum, f.progress, 1, "toy", f.clock + 30 * 86400)->empty());

  // Lesson one answered throughout: its three structures are taught; a month later all three are
  // due, and the review asks only lesson one's questions until the queue is empty.
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "one"));
  while (!engine.atEnd()) {
    auto step = engine.current();
    if (step->kind == StepKind::Question) {
      if (step->questionKind == quiz::QuestionKind::Identify)
        REQUIRE(engine.answer(choice(indexOf(step->choiceIds, step->structure)), {}, 0));
      else REQUIRE(engine.answer(text(step->structure), {}, 0));
    }
    REQUIRE(engine.next());
  }
  REQUIRE(engine.finish());
  auto taught = taughtStructures(f.curriculum, f.progress, 1, "toy");
  REQUIRE(taught->size() == 3);
  CHECK((*taught)[0].structureId == "cochlea");
  f.clock += 30 * 86400;
  CHECK(reviewQueue(f.curriculum, f.progress, 1, "toy", f.clock)->size() == 3);
  std::set<std::string> reviewed;
  for (int i = 0; i < 10; ++i) {
    auto q = chooseReviewQuestion(f.curriculum, f.progress, 1, "toy", f.clock);
    REQUIRE(q);
    if (!q->has_value()) break;
    CHECK((*q)->id.rfind("one.", 0) == 0);
    reviewed.insert((*q)->target);
    auto resolved = quiz::resolveQuestion(**q, f.keys);
    REQUIRE(resolved);
    quiz::Answer a = (*q)->kind == quiz::QuestionKind::Identify ? choice(resolved->keyChoice) : text((*q)->target);
    REQUIRE(answerReview(f.curriculum, f.progress, f.keys, reviewOf(**q, a), f.options()));
  }
  CHECK(reviewed == std::set<std::string>{"cochlea", "stapes", "vestibule"});
  CHECK(reviewQueue(f.curriculum, f.progress, 1, "toy", f.clock)->empty());
}

TEST_CASE("LessonEngine_BackShowsThePreviousStepWithItsFeedback_AndOutcomesReviewEveryQuestion") {
  Fixture f;
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "one"));
  CHECK_FALSE(engine.back());  // the first step has nothing before it
  REQUIRE(engine.next());
  REQUIRE(engine.answer(text("vestibule"), {}, 100));  // wrong: the cochlea is asked
  REQUIRE(engine.next());
  CHECK(engine.current()->position == 3);
  REQUIRE(engine.back());
  auto step = engine.current();
  REQUIRE(step);
  CHECK(step->position == 2);
  REQUIRE(step->feedback.has_value());  // the answered question comes back with its feedback
  CHECK_FALSE(step->feedback->correct);
  CHECK_FALSE(engine.answer(text("cochlea"), {}, 10));  // and its answer stands
  REQUIRE(engine.back());
  CHECK(engine.current()->position == 1);
  // Forward again to the end, answering the rest.
  for (int i = 0; i < 3; ++i) REQUIRE(engine.next());
  const int right = indexOf(engine.current()->choiceIds, "stapes");
  REQUIRE(engine.answer(choice(right), {}, 100));
  REQUIRE(engine.next());
  REQUIRE(engine.answer(text("Vestibule"), {}, 100));
  REQUIRE(engine.next());
  CHECK(engine.atEnd());
  REQUIRE(engine.back());  // from the end: the last step again
  CHECK(engine.current()->position == 5);
  REQUIRE(engine.next());

  const std::vector<QuestionOutcome> outcomes = engine.outcomes();
  REQUIRE(outcomes.size() == 3);
  CHECK(outcomes[0].questionId == "one.q1");
  CHECK(outcomes[0].yourAnswer == "\"vestibule\"");
  CHECK(outcomes[0].rightAnswer == "Cochlea");
  REQUIRE(outcomes[0].grade.has_value());
  CHECK_FALSE(outcomes[0].grade->correct);
  CHECK(outcomes[0].scene.structure == "cochlea");  // the answer highlighted
  CHECK(outcomes[1].yourAnswer == "Stapes");
  CHECK(outcomes[1].rightAnswer == "Stapes");
  CHECK(outcomes[1].grade->correct);
  CHECK(outcomes[2].grade->correct);
}

TEST_CASE("LessonEngine_SideAskedWithoutASide_IsPartialAndRatedHard_SideNotAskedIsRight") {
  Fixture f;
  Course& c = f.curriculum.courseList[0];
  quiz::Question asked = nameQ("three.q1", "orbit_left");
  asked.askSide = true;
  Lesson three;
  three.id = "three";
  three.courseId = "toy";
  three.title = "Lesson three";
  three.steps = {questionStep(asked), questionStep(nameQ("three.q2", "orbit_right"))};
  c.lessons.push_back(three);
  Structure left, right;
  left.label = 6, left.id = "orbit_left", left.displayName = "Orbit (left)";
  right.label = 7, right.id = "orbit_right", right.displayName = "Orbit (right)";
  f.curriculum.datasets["phantom"].push_back(left);
  f.curriculum.datasets["phantom"].push_back(right);
  f.keys.structureIds.push_back("orbit_left");
  f.keys.structureIds.push_back("orbit_right");
  LessonEngine engine(f.curriculum, f.progress, f.keys, f.options());
  REQUIRE(engine.start(1, "three"));
  auto g = engine.answer(text("orbit"), {}, 60'000);
  REQUIRE(g);
  CHECK_FALSE(g->correct);
  CHECK(g->score == 0.5);
  CHECK(g->feedback.find("Which side?") == 0);
  CHECK((f.progress.log.back().rating == Rating::Hard));  // FSRS follows the partial grade
  REQUIRE(engine.next());
  g = engine.answer(text("orbit"), {}, 60'000);
  REQUIRE(g);
  CHECK(g->correct);
  CHECK(g->feedback.find("right") == std::string::npos);
  CHECK((f.progress.log.back().rating == Rating::Good));
}
