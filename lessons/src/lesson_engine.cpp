#include "lessons/lesson_engine.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <set>

#include "quiz/elo.h"

namespace at::lessons {
namespace {

bool isQuestion(const Lesson& lesson, int index) {
  return lesson.steps[std::size_t(index)].kind == StepKind::Question;
}

UnixSeconds clockNow(const EngineOptions& options) {
  if (options.clock) return options.clock();
  return std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

// What one graded answer does to the learner model: the FSRS rating and the structure's next memory
// state, and the Elo update of the user's ability against the question's difficulty.
Result<LearnerUpdate> learnerUpdate(ProgressRepository& progress, std::int64_t userId, const quiz::Question& question,
                                    const quiz::Grade& grade, std::int64_t latencyMs, UnixSeconds at,
                                    const EngineOptions& options) {
  auto before = progress.progress(userId, question.target);
  if (!before) return tl::unexpected(before.error());
  const StructureProgress previous = before->value_or(StructureProgress{userId, question.target});
  auto ability = progress.ability(userId);
  if (!ability) return tl::unexpected(ability.error());
  auto difficulty = progress.questionDifficulty(question.id);
  if (!difficulty) return tl::unexpected(difficulty.error());
  if (auto valid = validate(options.fsrs); !valid) return tl::unexpected(valid.error());
  LearnerUpdate update;
  const quiz::EloUpdate elo = quiz::updateElo(ability->value_or(quiz::kDefaultAbility),
                                              difficulty->value_or(question.difficulty), grade.score, options.eloK);
  update.abilityAfter = elo.ability;
  update.difficultyAfter = elo.difficulty;
  update.rating = ratingFor(grade.correct, grade.score, question.kind, latencyMs);
  update.memoryBefore = previous.memory;
  update.progress = scheduleAnswer(previous, update.rating, grade.correct, at, Fsrs(options.fsrs));
  return update;
}

GradedAnswer gradedAnswer(const quiz::Question& question, const quiz::Answer& answer, const quiz::Grade& grade,
                          std::int64_t latencyMs, const RenderState& render, UnixSeconds at) {
  GradedAnswer g;
  g.questionId = question.id;
  g.structureId = question.target;
  g.answer = answer;
  g.correct = grade.correct;
  g.score = grade.score;
  g.latencyMs = latencyMs;
  g.render = render;
  g.answeredAt = at;
  return g;
}

}  // namespace

quiz::GradingContext gradingContext(const std::vector<Structure>& structures, const Course& course) {
  quiz::GradingContext context;
  for (const Structure& s : structures) {
    quiz::NameEntry entry{s.id, {}};
    if (!s.displayName.empty()) entry.names.push_back(s.displayName);
    std::string spaced = s.id;
    std::replace(spaced.begin(), spaced.end(), '_', ' ');
    entry.names.push_back(spaced);
    if (const auto it = course.synonyms.find(s.id); it != course.synonyms.end()) {
      entry.names.insert(entry.names.end(), it->second.begin(), it->second.end());
    }
    context.names.push_back(std::move(entry));
  }
  return context;
}

LessonEngine::LessonEngine(CurriculumRepository& curriculum, ProgressRepository& progress, quiz::KeyComputer& keys,
                           EngineOptions options)
    : curriculum_(curriculum), progress_(progress), keys_(keys), options_(std::move(options)) {}

UnixSeconds LessonEngine::now() const { return clockNow(options_); }

const Attempt& LessonEngine::attempt() const {
  assert(attempt_ && "LessonEngine::attempt: call start() first");
  return *attempt_;
}

Status LessonEngine::start(std::int64_t userId, const std::string& lessonId, LessonMode mode) {
  attempt_.reset();
  resumed_ = false;
  auto lesson = curriculum_.lesson(lessonId);
  if (!lesson) return tl::unexpected(lesson.error());

  std::string missing;
  for (const std::string& pre : lesson->prerequisites) {
    auto done = progress_.hasFinished(userId, pre);
    if (!done) return tl::unexpected(done.error());
    if (*done) continue;
    auto preLesson = curriculum_.lesson(pre);
    missing += (missing.empty() ? "" : ", ") + std::string("'") + pre + "'" +
               (preLesson ? " (" + preLesson->title + ")" : std::string());
  }
  if (!missing.empty()) {
    return fail("lesson '" + lessonId + "' (" + lesson->title + ") needs " + missing + " finished first");
  }
  for (std::size_t i = 0; i < lesson->steps.size(); ++i) {
    if (lesson->steps[i].kind == StepKind::Study) {
      return fail("lesson '" + lessonId + "': step " + std::to_string(i) +
                  " is a study comparison, which lessons do not run (use the study command)");
    }
  }
  auto course = curriculum_.course(lesson->courseId);
  if (!course) return tl::unexpected(course.error());
  auto structures = curriculum_.structures(course->datasetId);
  if (!structures) return tl::unexpected(structures.error());

  std::vector<std::optional<quiz::ResolvedQuestion>> resolved(lesson->steps.size());
  for (std::size_t i = 0; i < lesson->steps.size(); ++i) {
    if (lesson->steps[i].kind != StepKind::Question) continue;
    auto r = quiz::resolveQuestion(lesson->steps[i].question, keys_);
    if (!r) return tl::unexpected(withContext("lesson '" + lessonId + "'", r.error()));
    resolved[i] = std::move(*r);
  }

  auto open = progress_.openAttempt(userId, lessonId);
  if (!open) return tl::unexpected(open.error());
  Attempt attempt;
  if (*open) {
    attempt = **open;
    resumed_ = true;
  } else {
    auto started = progress_.startAttempt(userId, lessonId, mode, now());
    if (!started) return tl::unexpected(started.error());
    attempt = *started;
  }

  lesson_ = std::move(*lesson);
  course_ = std::move(*course);
  structures_ = std::move(*structures);
  resolved_ = std::move(resolved);
  grades_.assign(lesson_.steps.size(), std::nullopt);
  shown_.clear();
  for (int i = 0; i < int(lesson_.steps.size()); ++i) {
    if (attempt.mode == LessonMode::Guided || isQuestion(lesson_, i)) shown_.push_back(i);
  }

  if (resumed_) {
    auto responses = progress_.responses(attempt.id);
    if (!responses) return tl::unexpected(responses.error());
    const quiz::GradingContext context = gradingContext(structures_, course_);
    for (const Response& response : *responses) {
      if (response.stepIndex < 0 || response.stepIndex >= int(lesson_.steps.size()) ||
          !resolved_[std::size_t(response.stepIndex)]) {
        continue;  // the lesson changed since: that response no longer maps to a question step
      }
      quiz::Grade grade{response.correct, response.score, ""};
      if (auto regraded = quiz::grade(*resolved_[std::size_t(response.stepIndex)], response.answer, context)) {
        grade.feedback = regraded->feedback;
      }
      grades_[std::size_t(response.stepIndex)] = grade;
    }
  }
  // Resume after the last answered step, or at an earlier question left unanswered.
  std::size_t cursor = 0;
  std::optional<std::size_t> firstUnanswered;
  for (std::size_t p = 0; p < shown_.size(); ++p) {
    const int index = shown_[p];
    if (grades_[std::size_t(index)]) cursor = p + 1;
    else if (isQuestion(lesson_, index) && !firstUnanswered) firstUnanswered = p;
  }
  if (firstUnanswered) cursor = std::min(cursor, *firstUnanswered);
  cursor_ = cursor;
  attempt_ = attempt;
  return {};
}

bool LessonEngine::atEnd() const { return cursor_ >= shown_.size(); }

Result<StepView> LessonEngine::current() const {
  if (!attempt_) return fail("no lesson started");
  if (atEnd()) return fail("lesson '" + lesson_.id + "': no more steps; finish the attempt");
  const int index = shown_[cursor_];
  const Step& step = lesson_.steps[std::size_t(index)];
  const quiz::GradingContext context = gradingContext(structures_, course_);
  StepView view;
  view.index = index;
  view.position = int(cursor_) + 1;
  view.count = int(shown_.size());
  view.kind = step.kind;
  view.labelsVisible = attempt_->mode == LessonMode::Guided;
  if (step.kind == StepKind::Show) {
    view.structure = step.show.structure;
    view.structureName = view.labelsVisible ? context.displayName(step.show.structure) : "";
    view.presetId = step.show.presetId;
    view.view = step.show.view;
    view.title = step.show.title;
    view.text = step.show.text;
  } else {
    const quiz::ResolvedQuestion& q = *resolved_[std::size_t(index)];
    view.structure = q.question.target;
    view.structureName = view.labelsVisible && q.question.kind != quiz::QuestionKind::Identify &&
                                 q.question.kind != quiz::QuestionKind::Name
                             ? context.displayName(q.question.target)
                             : "";
    view.questionId = q.question.id;
    view.questionKind = q.question.kind;
    view.prompt = q.question.prompt;
    view.choiceIds = q.choices;
    for (const std::string& id : q.choices) view.choiceNames.push_back(context.displayName(id));
    view.feedback = grades_[std::size_t(index)];
  }
  return view;
}

Result<quiz::ResolvedQuestion> LessonEngine::currentQuestion() const {
  if (!attempt_) return fail("no lesson started");
  if (atEnd()) return fail("lesson '" + lesson_.id + "': no more steps");
  const int index = shown_[cursor_];
  if (!resolved_[std::size_t(index)]) return fail("lesson '" + lesson_.id + "': the current step is not a question");
  return *resolved_[std::size_t(index)];
}

Result<quiz::Grade> LessonEngine::answer(const quiz::Answer& answer, const RenderState& render,
                                         std::int64_t latencyMs) {
  if (!attempt_) return fail("no lesson started");
  if (attempt_->finishedAt) return fail("lesson '" + lesson_.id + "': the attempt is finished");
  if (atEnd()) return fail("lesson '" + lesson_.id + "': no more steps");
  const int index = shown_[cursor_];
  if (!resolved_[std::size_t(index)]) {
    return fail("lesson '" + lesson_.id + "': step " + std::to_string(cursor_ + 1) + " is not a question");
  }
  if (grades_[std::size_t(index)]) {
    return fail("lesson '" + lesson_.id + "': step " + std::to_string(cursor_ + 1) + " is already answered");
  }
  const quiz::ResolvedQuestion& question = *resolved_[std::size_t(index)];
  auto grade = quiz::grade(question, answer, gradingContext(structures_, course_));
  if (!grade) return tl::unexpected(grade.error());

  const UnixSeconds at = now();
  auto update = learnerUpdate(progress_, attempt_->userId, question.question, *grade, latencyMs, at, options_);
  if (!update) return tl::unexpected(update.error());

  AnswerRecord record;
  static_cast<GradedAnswer&>(record.response) = gradedAnswer(question.question, answer, *grade, latencyMs, render, at);
  record.response.attemptId = attempt_->id;
  record.response.stepIndex = index;
  record.update = std::move(*update);
  auto stored = progress_.recordAnswer(record);
  if (!stored) return tl::unexpected(withContext("recording the answer", stored.error()));

  grades_[std::size_t(index)] = *grade;
  return *grade;
}

Status LessonEngine::next() {
  if (!attempt_) return fail("no lesson started");
  if (atEnd()) return fail("lesson '" + lesson_.id + "': no more steps");
  const int index = shown_[cursor_];
  if (resolved_[std::size_t(index)] && !grades_[std::size_t(index)]) {
    return fail("lesson '" + lesson_.id + "': answer the question of step " + std::to_string(cursor_ + 1) + " first");
  }
  ++cursor_;
  return {};
}

Result<double> LessonEngine::finish() {
  if (!attempt_) return fail("no lesson started");
  if (attempt_->finishedAt) return attempt_->score;
  double total = 0;
  int questions = 0, unanswered = 0;
  for (const int index : shown_) {
    if (!resolved_[std::size_t(index)]) continue;
    ++questions;
    if (grades_[std::size_t(index)]) total += grades_[std::size_t(index)]->score;
    else ++unanswered;
  }
  if (unanswered > 0) {
    return fail("lesson '" + lesson_.id + "': " + std::to_string(unanswered) + " question(s) not answered yet");
  }
  const double score = questions > 0 ? total / questions : 1.0;
  const UnixSeconds at = now();
  if (auto ok = progress_.finishAttempt(attempt_->id, at, score); !ok) return tl::unexpected(ok.error());
  attempt_->finishedAt = at;
  attempt_->score = score;
  cursor_ = shown_.size();
  return score;
}

Result<double> LessonEngine::ability() const {
  if (!attempt_) return fail("no lesson started");
  auto ability = progress_.ability(attempt_->userId);
  if (!ability) return tl::unexpected(ability.error());
  return ability->value_or(quiz::kDefaultAbility);
}

Result<std::vector<StructureProgress>> reviewQueue(ProgressRepository& progress, std::int64_t userId,
                                                   UnixSeconds now) {
  auto all = progress.allProgress(userId);
  if (!all) return tl::unexpected(all.error());
  return dueForReview(std::move(*all), now);
}

Result<std::optional<quiz::Question>> chooseReviewQuestion(CurriculumRepository& curriculum,
                                                           ProgressRepository& progress, std::int64_t userId,
                                                           const std::string& courseId, UnixSeconds now) {
  auto course = curriculum.course(courseId);
  if (!course) return tl::unexpected(course.error());
  auto all = progress.allProgress(userId);
  if (!all) return tl::unexpected(all.error());
  std::set<std::string> answered, due;
  for (const StructureProgress& p : *all) {
    if (p.answered > 0) answered.insert(p.structureId);
  }
  for (const StructureProgress& p : dueForReview(*all, now)) due.insert(p.structureId);
  auto ability = progress.ability(userId);
  if (!ability) return tl::unexpected(ability.error());

  std::vector<quiz::Question> questions;
  std::vector<quiz::SelectionCandidate> candidates;
  for (const Lesson& lesson : course->lessons) {
    for (const Step& step : lesson.steps) {
      if (step.kind != StepKind::Question) continue;
      const quiz::Question& q = step.question;
      auto difficulty = progress.questionDifficulty(q.id);
      if (!difficulty) return tl::unexpected(difficulty.error());
      candidates.push_back({q.id, difficulty->value_or(q.difficulty), due.count(q.target) > 0 || !answered.count(q.target)});
      questions.push_back(q);
    }
  }
  const auto chosen = quiz::chooseAdaptive(candidates, ability->value_or(quiz::kDefaultAbility));
  if (!chosen) return std::optional<quiz::Question>{};
  return std::optional<quiz::Question>(questions[*chosen]);
}

Result<quiz::Grade> answerReview(CurriculumRepository& curriculum, ProgressRepository& progress,
                                 quiz::KeyComputer& keys, const ReviewAnswer& review, const EngineOptions& options) {
  auto course = curriculum.course(review.courseId);
  if (!course) return tl::unexpected(course.error());
  const quiz::Question* stored = nullptr;
  for (const Lesson& lesson : course->lessons) {
    for (const Step& step : lesson.steps) {
      if (step.kind == StepKind::Question && step.question.id == review.question.id) stored = &step.question;
    }
  }
  if (!stored) {
    return fail("review: question '" + review.question.id + "' is not in course '" + review.courseId + "'");
  }
  auto structures = curriculum.structures(course->datasetId);
  if (!structures) return tl::unexpected(structures.error());
  auto resolved = quiz::resolveQuestion(*stored, keys);
  if (!resolved) return tl::unexpected(withContext("review", resolved.error()));
  auto grade = quiz::grade(*resolved, review.answer, gradingContext(*structures, *course));
  if (!grade) return tl::unexpected(grade.error());

  const UnixSeconds at = clockNow(options);
  auto update = learnerUpdate(progress, review.userId, *stored, *grade, review.latencyMs, at, options);
  if (!update) return tl::unexpected(update.error());

  ReviewRecord record;
  static_cast<GradedAnswer&>(record.response) =
      gradedAnswer(*stored, review.answer, *grade, review.latencyMs, review.render, at);
  record.response.userId = review.userId;
  record.update = std::move(*update);
  auto recorded = progress.recordReviewAnswer(record);
  if (!recorded) return tl::unexpected(withContext("review", recorded.error()));
  return *grade;
}

}  // namespace at::lessons
