#include "lessons/lesson_engine.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <set>

#include "lessons/structure_catalogue.h"
#include "quiz/elo.h"
#include "quiz/sided_names.h"

namespace at::lessons {
namespace {

bool isQuestion(const Lesson& lesson, int index) {
  return lesson.steps[std::size_t(index)].kind == StepKind::Question;
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
  StructureProgress never;  // never answered: memory.phase == New
  never.userId = userId;
  never.structureId = question.target;
  const StructureProgress previous = before->value_or(never);
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

Result<std::string> unfinishedLessons(CurriculumRepository& curriculum, ProgressRepository& progress,
                                      std::int64_t userId, const std::vector<std::string>& lessonIds) {
  std::string missing;
  for (const std::string& id : lessonIds) {
    auto done = progress.hasFinished(userId, id);
    if (!done) return tl::unexpected(done.error());
    if (*done) continue;
    auto lesson = curriculum.lesson(id);
    missing += (missing.empty() ? "" : ", ") + std::string("'") + id + "'" +
               (lesson ? " (" + lesson->title + ")" : std::string());
  }
  return missing;
}

std::optional<QuestionScene> questionScene(const Course& course, const std::string& questionId) {
  for (const Lesson& lesson : course.lessons)
    for (const Step& step : lesson.steps)
      if (step.kind == StepKind::Question && step.question.id == questionId) return sceneFor(step);
  return std::nullopt;
}

quiz::GradingContext gradingContext(const std::vector<Structure>& structures, const Course& course) {
  quiz::GradingContext context;
  const StructureCatalogue* catalogue = shippedCatalogue(course.datasetId);
  for (const Structure& s : structures) {
    quiz::NameEntry entry;
    entry.structureId = s.id;
    if (!s.displayName.empty()) entry.names.push_back(s.displayName);
    std::string spaced = s.id;
    std::replace(spaced.begin(), spaced.end(), '_', ' ');
    entry.names.push_back(spaced);
    entry.side = quiz::sideOfName(s.displayName.empty() ? spaced : s.displayName);
    entry.baseName = quiz::withoutSide(s.displayName.empty() ? spaced : s.displayName);
    if (const CatalogueEntry* known = catalogue ? catalogue->find(s.id) : nullptr) {
      entry.names.push_back(known->name);
      entry.names.insert(entry.names.end(), known->synonyms.begin(), known->synonyms.end());
      entry.names.insert(entry.names.end(), known->latin.begin(), known->latin.end());
      entry.side = known->side;
      entry.baseName = known->name;
    }
    if (const auto it = course.synonyms.find(s.id); it != course.synonyms.end()) {
      entry.names.insert(entry.names.end(), it->second.begin(), it->second.end());
    }
    // Each spelling once, in the order above (the display name first).
    std::vector<std::string> unique;
    for (std::string& name : entry.names)
      if (std::find(unique.begin(), unique.end(), name) == unique.end()) unique.push_back(std::move(name));
    entry.names = std::move(unique);
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

  auto missing = unfinishedLessons(curriculum_, progress_, userId, lesson->prerequisites);
  if (!missing) return tl::unexpected(missing.error());
  if (!missing->empty()) {
    return fail("lesson '" + lessonId + "' (" + lesson->title + ") needs " + *missing + " finished first");
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
  answers_.assign(lesson_.steps.size(), std::nullopt);
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
      answers_[std::size_t(response.stepIndex)] = response.answer;
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
    view.scene = QuestionScene{step.show.structure, step.show.presetId, step.show.view, step.show.camera, step.show.clip};
  } else {
    view.scene = sceneFor(step);
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
  answers_[std::size_t(index)] = answer;
  return *grade;
}

Status LessonEngine::back() {
  if (!attempt_) return fail("no lesson started");
  if (cursor_ == 0) return fail("lesson '" + lesson_.id + "': this is the first step");
  --cursor_;
  return {};
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

namespace {

// The questions of the lessons of `course` that the user has started, in course order.
Result<std::vector<quiz::Question>> startedQuestions(ProgressRepository& progress, std::int64_t userId,
                                                     const Course& course) {
  auto attempts = progress.attempts(userId);
  if (!attempts) return tl::unexpected(attempts.error());
  std::set<std::string> started;
  for (const Attempt& a : *attempts) started.insert(a.lessonId);
  std::vector<quiz::Question> out;
  for (const Lesson& lesson : course.lessons) {
    if (!started.count(lesson.id)) continue;
    for (const Step& step : lesson.steps)
      if (step.kind == StepKind::Question) out.push_back(step.question);
  }
  return out;
}

}  // namespace

std::vector<std::string> taughtStructureIds(const Course& course, const std::vector<Attempt>& userAttempts,
                                            const std::vector<StructureProgress>& userMemories) {
  std::set<std::string> started, asked, taught;
  for (const Attempt& a : userAttempts) started.insert(a.lessonId);
  for (const Lesson& lesson : course.lessons)
    if (started.count(lesson.id))
      for (const Step& step : lesson.steps)
        if (step.kind == StepKind::Question) asked.insert(step.question.target);
  for (const StructureProgress& p : userMemories)
    if (p.answered > 0 && p.memory.phase != MemoryPhase::New && asked.count(p.structureId)) taught.insert(p.structureId);
  return {taught.begin(), taught.end()};
}

Result<std::vector<StructureProgress>> taughtStructures(CurriculumRepository& curriculum, ProgressRepository& progress,
                                                        std::int64_t userId, const std::string& courseId) {
  auto course = curriculum.course(courseId);
  if (!course) return tl::unexpected(course.error());
  auto attempts = progress.attempts(userId);
  if (!attempts) return tl::unexpected(attempts.error());
  auto all = progress.allProgress(userId);
  if (!all) return tl::unexpected(all.error());
  const std::vector<std::string> ids = taughtStructureIds(*course, *attempts, *all);
  std::vector<StructureProgress> taught;
  for (StructureProgress& p : *all)
    if (std::binary_search(ids.begin(), ids.end(), p.structureId)) taught.push_back(std::move(p));
  std::sort(taught.begin(), taught.end(),
            [](const StructureProgress& a, const StructureProgress& b) { return a.structureId < b.structureId; });
  return taught;
}

Result<std::vector<StructureProgress>> reviewQueue(CurriculumRepository& curriculum, ProgressRepository& progress,
                                                   std::int64_t userId, const std::string& courseId, UnixSeconds now) {
  auto taught = taughtStructures(curriculum, progress, userId, courseId);
  if (!taught) return tl::unexpected(taught.error());
  return dueForReview(std::move(*taught), now);
}

Result<std::optional<quiz::Question>> chooseReviewQuestion(CurriculumRepository& curriculum,
                                                           ProgressRepository& progress, std::int64_t userId,
                                                           const std::string& courseId, UnixSeconds now) {
  auto course = curriculum.course(courseId);
  if (!course) return tl::unexpected(course.error());
  auto queue = reviewQueue(curriculum, progress, userId, courseId, now);
  if (!queue) return tl::unexpected(queue.error());
  std::set<std::string> due;
  for (const StructureProgress& p : *queue) due.insert(p.structureId);
  if (due.empty()) return std::optional<quiz::Question>{};
  auto questions = startedQuestions(progress, userId, *course);
  if (!questions) return tl::unexpected(questions.error());
  auto ability = progress.ability(userId);
  if (!ability) return tl::unexpected(ability.error());

  std::vector<quiz::SelectionCandidate> candidates;
  for (const quiz::Question& q : *questions) {
    auto difficulty = progress.questionDifficulty(q.id);
    if (!difficulty) return tl::unexpected(difficulty.error());
    candidates.push_back({q.id, difficulty->value_or(q.difficulty), due.count(q.target) > 0});
  }
  const auto chosen = quiz::chooseAdaptive(candidates, ability->value_or(quiz::kDefaultAbility));
  if (!chosen) return std::optional<quiz::Question>{};
  return std::optional<quiz::Question>((*questions)[*chosen]);
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
