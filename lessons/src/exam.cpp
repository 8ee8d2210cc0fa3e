#include "lessons/exam.h"

#include <algorithm>
#include <cassert>
#include <set>

namespace at::lessons {
namespace {

const char* kindWord(quiz::QuestionKind kind) { return quiz::toString(kind); }

// The question an exam item asks, before its keys are resolved.
quiz::Question itemQuestion(const ExamSpec& exam, const Structure& target, quiz::QuestionKind kind,
                            ExamLocateView view) {
  quiz::Question q;
  q.id = exam.id + "." + kindWord(kind) + "." + target.id;
  q.kind = kind;
  q.target = target.id;
  const std::string name = quiz::nameInSentence(target.displayName.empty() ? target.id : target.displayName);
  switch (kind) {
    case quiz::QuestionKind::Locate:
      q.prompt = "Locate the " + name + (view == ExamLocateView::Slice ? " on the slice." : " in the view.");
      break;
    case quiz::QuestionKind::Identify:
      q.prompt = "Which structure is marked?";
      q.distractors = 3;
      break;
    default:
      q.prompt = "Name the marked structure.";
      break;
  }
  return q;
}

}  // namespace

Result<std::pair<Course, ExamSpec>> findExam(CurriculumRepository& curriculum, const std::string& examId) {
  auto courses = curriculum.courses();
  if (!courses) return tl::unexpected(courses.error());
  for (Course& c : *courses)
    for (const ExamSpec& e : c.exams)
      if (e.id == examId) {
        ExamSpec exam = e;
        return std::make_pair(std::move(c), std::move(exam));
      }
  return fail("unknown exam '" + examId + "'");
}

const Step* lessonLocateStep(const Course& course, const std::string& structureId) {
  for (const Lesson& lesson : course.lessons)
    for (const Step& step : lesson.steps)
      if (step.kind == StepKind::Question && step.question.kind == quiz::QuestionKind::Locate &&
          step.question.target == structureId)
        return &step;
  return nullptr;
}

namespace {

// Whether `exam` can ask structure `id` to be located (see examPoolSize).
bool locatable(const ExamSpec& exam, const Course* course, const std::string& id) {
  const bool otherKinds = std::any_of(exam.kinds.begin(), exam.kinds.end(),
                                      [](quiz::QuestionKind k) { return k != quiz::QuestionKind::Locate; });
  return !course || !otherKinds || lessonLocateStep(*course, id);
}

}  // namespace

std::size_t examPoolSize(const ExamSpec& exam, const Course* course) {
  std::size_t pool = 0;
  for (const std::string& id : exam.structures)
    for (quiz::QuestionKind k : exam.kinds) pool += k != quiz::QuestionKind::Locate || locatable(exam, course, id);
  return pool;
}

Result<std::vector<ExamItem>> drawExamItems(const ExamSpec& exam, const std::vector<Structure>& structures,
                                            quiz::KeyComputer& keys, const std::string& seed, const Course* course) {
  const auto find = [&](const std::string& id) -> const Structure* {
    for (const Structure& s : structures)
      if (s.id == id) return &s;
    return nullptr;
  };
  for (const std::string& id : exam.structures)
    if (!find(id)) return fail("exam '" + exam.id + "': structure '" + id + "' is not in the course's dataset");

  // Every structure once (in a shuffled order), each with its own shuffled order of the kinds it
  // can be asked in, then round after round until `count` items: round r asks each structure its
  // r-th kind, and a structure with fewer kinds sits the later rounds out. A structure can be asked
  // to be located only when the course has a lesson view locating it (see the header), unless
  // locate is the exam's one kind or there is no course. So each structure's kind is drawn evenly
  // from the kinds it can be asked in, and no item is asked twice.
  const std::vector<std::string> order = quiz::stableShuffle(exam.structures, seed);
  std::vector<std::vector<std::string>> kindOrder;
  for (const std::string& id : order) {
    std::vector<std::string> kindNames;
    for (quiz::QuestionKind k : exam.kinds)
      if (k != quiz::QuestionKind::Locate || locatable(exam, course, id)) kindNames.push_back(kindWord(k));
    kindOrder.push_back(quiz::stableShuffle(kindNames, seed + "/" + id));
  }
  if (const std::size_t askable = examPoolSize(exam, course); askable < std::size_t(exam.count))
    return fail("exam '" + exam.id + "' asks " + std::to_string(exam.count) + " items, but its structures can be asked only " +
                std::to_string(askable) + " ways (a structure is located only where a lesson of the course locates it)");

  std::vector<ExamItem> items;
  int locateItems = 0;
  for (std::size_t round = 0; round < exam.kinds.size() && int(items.size()) < exam.count; ++round) {
    for (std::size_t i = 0; i < order.size() && int(items.size()) < exam.count; ++i) {
      if (round >= kindOrder[i].size()) continue;
      const Structure& target = *find(order[i]);
      auto kind = quiz::parseQuestionKind(kindOrder[i][round]);
      if (!kind) return tl::unexpected(kind.error());
      const Step* lessonStep = course ? lessonLocateStep(*course, target.id) : nullptr;
      ExamItem item;
      item.position = int(items.size());
      if (*kind == quiz::QuestionKind::Locate)
        item.locateView = exam.locateViews[std::size_t(locateItems++) % exam.locateViews.size()];
      quiz::Question question = itemQuestion(exam, target, *kind, item.locateView);
      if (*kind == quiz::QuestionKind::Locate && lessonStep) question.toleranceMm = lessonStep->question.toleranceMm;
      auto resolved = quiz::resolveQuestion(question, keys);
      if (!resolved) return tl::unexpected(withContext("exam '" + exam.id + "'", resolved.error()));
      item.question = std::move(*resolved);
      item.scene.structure = target.id;
      if (*kind == quiz::QuestionKind::Locate && lessonStep) {
        item.scene = sceneFor(*lessonStep);
        items.push_back(std::move(item));
        continue;
      }
      if (*kind == quiz::QuestionKind::Locate) {
        // The region without marking the target: the view of its nearest neighbour.
        auto distances = keys.distancesFrom(target.id);
        if (!distances) return tl::unexpected(withContext("exam '" + exam.id + "'", distances.error()));
        const auto nearest = quiz::nearestStructures(target.id, *distances, 1);
        if (nearest.empty())
          return fail("exam '" + exam.id + "': no structure near '" + target.id + "' to show its region");
        item.scene.structure = nearest.front();
      }
      item.scene.presetId = item.scene.structure + "_wdt";
      items.push_back(std::move(item));
    }
  }
  return items;
}

ExamSession::ExamSession(CurriculumRepository& curriculum, ProgressRepository& progress, ExamRepository& exams,
                         quiz::KeyComputer& keys, EngineOptions options)
    : curriculum_(curriculum), progress_(progress), exams_(exams), keys_(keys), options_(std::move(options)) {}

UnixSeconds ExamSession::now() const { return clockNow(options_); }

const ExamAttempt& ExamSession::attempt() const {
  assert(attempt_ && "ExamSession::attempt: call start() first");
  return *attempt_;
}

Status ExamSession::start(std::int64_t userId, const std::string& examId) {
  attempt_.reset();
  items_.clear();
  resumed_ = false;
  auto found = findExam(curriculum_, examId);
  if (!found) return tl::unexpected(found.error());
  auto& [course, exam] = *found;

  auto missing = unfinishedLessons(curriculum_, progress_, userId, exam.prerequisites);
  if (!missing) return tl::unexpected(missing.error());
  if (!missing->empty())
    return fail("exam '" + examId + "' (" + exam.title + ") needs " + *missing + " finished first");

  auto structures = curriculum_.structures(course.datasetId);
  if (!structures) return tl::unexpected(structures.error());
  context_ = gradingContext(*structures, course);

  auto open = exams_.openExamAttempt(userId, examId);
  if (!open) return tl::unexpected(open.error());
  if (*open) {
    auto items = exams_.examItems((*open)->id);
    if (!items) return tl::unexpected(items.error());
    attempt_ = **open;
    items_ = std::move(*items);
    resumed_ = true;
  } else {
    auto previous = exams_.examAttempts(userId);
    if (!previous) return tl::unexpected(previous.error());
    const auto tries = std::count_if(previous->begin(), previous->end(),
                                     [&](const ExamAttempt& a) { return a.examId == examId; });
    const std::string seed = examId + "/" + std::to_string(userId) + "/" + std::to_string(tries);
    auto items = drawExamItems(exam, *structures, keys_, seed, &course);
    if (!items) return tl::unexpected(items.error());
    ExamAttempt a;
    a.userId = userId;
    a.examId = examId;
    a.courseId = course.id;
    a.startedAt = now();
    a.deadline = a.startedAt + exam.timeLimitS;
    auto started = exams_.startExamAttempt(a, *items);
    if (!started) return tl::unexpected(started.error());
    attempt_ = *started;
    items_ = std::move(*items);
  }
  course_ = std::move(course);
  exam_ = std::move(exam);
  return {};
}

UnixSeconds ExamSession::secondsLeft() const {
  if (!attempt_ || attempt_->finishedAt) return 0;
  return std::max<UnixSeconds>(0, attempt_->deadline - now());
}

bool ExamSession::finished() const { return attempt_ && attempt_->finishedAt.has_value(); }

std::optional<int> ExamSession::nextUnanswered() const {
  for (const ExamItem& item : items_)
    if (!item.answer) return item.position;
  return std::nullopt;
}

Result<ExamItemView> ExamSession::item(int position) const {
  if (!attempt_) return fail("no exam started");
  if (position < 0 || position >= int(items_.size()))
    return fail("exam '" + exam_.id + "' has items 1.." + std::to_string(items_.size()));
  const ExamItem& item = items_[std::size_t(position)];
  ExamItemView v;
  v.position = position;
  v.count = int(items_.size());
  v.kind = item.question.question.kind;
  v.prompt = item.question.question.prompt;
  v.choiceIds = item.question.choices;
  for (const std::string& id : v.choiceIds) v.choiceNames.push_back(context_.displayName(id));
  v.locateView = item.locateView;
  v.scene = item.scene;
  v.target = item.question.question.target;
  v.answered = item.answer.has_value();
  return v;
}

Result<quiz::ResolvedQuestion> ExamSession::itemQuestion(int position) const {
  if (!attempt_) return fail("no exam started");
  if (position < 0 || position >= int(items_.size())) return fail("no exam item " + std::to_string(position + 1));
  return items_[std::size_t(position)].question;
}

Status ExamSession::answer(int position, const quiz::Answer& given, std::int64_t latencyMs, const RenderState& render) {
  if (!attempt_) return fail("no exam started");
  if (attempt_->finishedAt) return fail("exam '" + exam_.id + "': this attempt is finished");
  if (position < 0 || position >= int(items_.size())) return fail("no exam item " + std::to_string(position + 1));
  const UnixSeconds at = now();
  if (at >= attempt_->deadline) return fail("exam '" + exam_.id + "': the time is up; the answer was not recorded");
  ExamItem& item = items_[std::size_t(position)];
  if (item.answer) return fail("exam item " + std::to_string(position + 1) + " is already answered");
  auto grade = quiz::grade(item.question, given, context_);
  if (!grade) return tl::unexpected(grade.error());
  auto update = learnerUpdate(progress_, attempt_->userId, item.question.question, *grade, latencyMs, at, options_);
  if (!update) return tl::unexpected(update.error());

  ExamAnswerRecord record;
  record.attemptId = attempt_->id;
  record.position = position;
  record.answer.questionId = item.question.question.id;
  record.answer.structureId = item.question.question.target;
  record.answer.answer = given;
  record.answer.correct = grade->correct;
  record.answer.score = grade->score;
  record.answer.latencyMs = latencyMs;
  record.answer.render = render;
  record.answer.answeredAt = at;
  record.update = std::move(*update);
  if (auto stored = exams_.recordExamAnswer(record); !stored)
    return tl::unexpected(withContext("recording the exam answer", stored.error()));
  item.answer = given;
  item.correct = grade->correct;
  item.score = grade->score;
  item.latencyMs = latencyMs;
  item.answeredAt = at;
  return {};
}

Result<ExamResult> ExamSession::results() const {
  ExamResult r;
  double total = 0;
  for (const ExamItem& item : items_) {
    ExamItemResult x;
    x.position = item.position;
    x.structure = item.question.question.target;
    x.kind = item.question.question.kind;
    x.answered = item.answer.has_value();
    x.prompt = item.question.question.prompt;
    x.rightAnswer = rightAnswerText(item.question, context_);
    if (item.answer) x.yourAnswer = answerText(item.question, *item.answer, context_);
    x.scene = showMeScene(item.scene, x.structure);
    if (item.answer) {
      auto grade = quiz::grade(item.question, *item.answer, context_);
      if (!grade) return tl::unexpected(grade.error());
      x.correct = grade->correct;
      x.score = grade->score;
      x.feedback = grade->feedback;
      ++r.answered;
    } else {
      x.feedback = "Not answered: this is the " + quiz::nameInSentence(context_.displayName(x.structure)) + ".";
    }
    if (x.correct) ++r.correct;
    total += x.score;
    r.items.push_back(std::move(x));
  }
  r.score = items_.empty() ? 0 : total / double(items_.size());
  if (exam_.passScore) r.passed = r.score >= *exam_.passScore;
  return r;
}

Result<ExamResult> ExamSession::finish() {
  if (!attempt_) return fail("no exam started");
  auto r = results();
  if (!r) return tl::unexpected(r.error());
  if (!attempt_->finishedAt) {
    const UnixSeconds at = std::min(now(), attempt_->deadline);
    if (auto ok = exams_.finishExamAttempt(attempt_->id, at, r->score, r->passed); !ok) return tl::unexpected(ok.error());
    attempt_->finishedAt = at;
    attempt_->score = r->score;
    attempt_->passed = r->passed;
  }
  r->timeRanOut = *attempt_->finishedAt >= attempt_->deadline;
  return r;
}

}  // namespace at::lessons
