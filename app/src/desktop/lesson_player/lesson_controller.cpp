// [SECTIONS] user and lists · running a lesson · answers · review
#include "lesson_player/lesson_controller.h"

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <map>
#include <set>

#include "class_practice.h"
#include "quiz/answer_json.h"
#include "quiz/grading.h"
#include "quiz/keys.h"

namespace at::app {

namespace {

using json = nlohmann::json;
using SteadyClock = std::chrono::steady_clock;

lessons::UnixSeconds unixNow() { return lessons::UnixSeconds(std::time(nullptr)); }

// The structure a question's view must also show: a locate question's target (its scene is a
// neighbouring region, which alone may leave the target outside the view).
std::string locateTarget(const quiz::ResolvedQuestion& q) {
  return q.question.kind == quiz::QuestionKind::Locate ? q.question.target : std::string();
}

}  // namespace

bool namesGiveAway(quiz::QuestionKind kind) {
  return kind == quiz::QuestionKind::Locate || kind == quiz::QuestionKind::Identify || kind == quiz::QuestionKind::Name;
}

LessonController::LessonController(LearningSession& session, std::string userName, std::string viewDataset,
                                   EventSink events, ShowStructure show, RenderStateSource renderState)
    : session_(session),
      userName_(std::move(userName)),
      viewDataset_(std::move(viewDataset)),
      events_(std::move(events)),
      show_(std::move(show)),
      renderState_(std::move(renderState)) {}

LessonController::~LessonController() = default;

// ---------------------------------------------------------------------------------------------
// User and lists

namespace {
// The user named `name` as stored, or one not stored yet (id 0: no records can name it).
Result<lessons::User> userOrUnstored(LearningSession& session, const std::string& name) {
  auto found = session.users().findUser(name);
  if (!found) return tl::unexpected(found.error());
  if (*found) return **found;
  lessons::User unstored;
  unstored.name = name;
  unstored.role = lessons::Role::Student;
  return unstored;
}
}  // namespace

Status LessonController::ready() {
  if (user_) return {};
  if (!readyError_.empty()) return fail(readyError_);  // failed once: not retried every frame
  auto user = userOrUnstored(session_, userName_);
  if (!user) return fail(readyError_ = "lessons: " + user.error().message);
  user_ = *user;
  return refresh();
}

Result<std::int64_t> LessonController::storedUserId() {
  if (auto st = ready(); !st) return tl::unexpected(st.error());
  if (user_->id != 0) return user_->id;
  auto user = session_.user(user_->name, LearningSession::NewUser::Create);
  if (!user) return tl::unexpected(withContext("lessons", user.error()));
  user_ = *user;
  return user_->id;
}

Status LessonController::switchUser(const std::string& name) {
  if (step_) return fail("leave the running lesson before changing the user");
  if (name.empty()) return fail("type a user name (a pseudonym)");
  if (auto st = ready(); !st) return st;
  auto user = userOrUnstored(session_, name);
  if (!user) return tl::unexpected(user.error());
  user_ = *user;
  userName_ = name;
  asked_.reset();
  finishedScore_.reset();
  engine_.reset();
  message_.clear();
  events_({{"event", "lesson_user"}, {"user", user->name}, {"id", user->id}});
  return refresh();
}

Status LessonController::selectCourse(int index) {
  if (index < 0 || index >= int(courses_.size())) return fail("no course " + std::to_string(index));
  courseIndex_ = index;
  return refresh();
}

void LessonController::preferCourse(const std::string& courseId) {
  preferredCourse_ = courseId;
  if (user_) (void)refresh();  // otherwise the first refresh (when the user is set) applies it
}

Status LessonController::selectCourse(const std::string& courseId) {
  if (auto st = ready(); !st) return st;
  auto it = std::find_if(courses_.begin(), courses_.end(), [&](const lessons::Course& c) { return c.id == courseId; });
  if (it == courses_.end()) return fail(ErrorKind::NotFound, "unknown course '" + courseId + "'");
  return selectCourse(int(it - courses_.begin()));
}

Status LessonController::refresh() {
  if (!user_) return fail("lessons: no user");
  auto courses = session_.curriculum().courses();
  if (!courses) return tl::unexpected(courses.error());
  courses_ = std::move(*courses);
  if (!preferredCourse_.empty()) {
    auto it = std::find_if(courses_.begin(), courses_.end(), [&](const lessons::Course& c) { return c.id == preferredCourse_; });
    if (it != courses_.end()) {
      courseIndex_ = int(it - courses_.begin());
      preferredCourse_.clear();
    }
  }
  courseIndex_ = std::clamp(courseIndex_, 0, std::max(0, int(courses_.size()) - 1));
  answersGoToClass_ = answersGoToClassServer(session_.database(), user_->name);  // `class join` may come meanwhile
  auto attempts = session_.progress().attempts(user_->id);
  if (!attempts) return tl::unexpected(attempts.error());
  std::set<std::string> finished;
  for (const lessons::Attempt& a : *attempts)
    if (a.finishedAt) finished.insert(a.lessonId);
  std::map<std::string, std::string> titles;  // prerequisites may lie in another course
  for (const lessons::Course& c : courses_)
    for (const lessons::Lesson& l : c.lessons) titles[l.id] = l.title;

  rows_.clear();
  if (!courses_.empty()) {
    for (const lessons::Lesson& l : courses_[std::size_t(courseIndex_)].lessons) {
      LessonRow row;
      row.id = l.id;
      row.title = l.title;
      row.summary = l.summary;
      for (const std::string& pre : l.prerequisites)
        if (!finished.count(pre)) row.missing.push_back(titles.count(pre) ? titles[pre] : pre);
      for (const lessons::Attempt& a : *attempts) {
        if (a.lessonId != l.id) continue;
        ++row.attempts;
        if (!a.finishedAt) row.open = true;
        else row.bestScore = std::max(row.bestScore.value_or(0.0), a.score);
      }
      row.questions = int(std::count_if(l.steps.begin(), l.steps.end(),
                                        [](const lessons::Step& st) { return st.kind == lessons::StepKind::Question; }));
      rows_.push_back(std::move(row));
    }
  }
  due_.clear();
  if (!courses_.empty()) {
    // The course the review button asks about: the same due list `progress` and `play --review` show.
    auto due = lessons::reviewQueue(session_.curriculum(), session_.progress(), user_->id,
                                    courses_[std::size_t(courseIndex_)].id, unixNow());
    if (!due) return tl::unexpected(due.error());
    due_ = std::move(*due);
    // The due list names its structures: the course's dataset's names (its ids where it is not here).
    if (auto list = session_.structures(courses_[std::size_t(courseIndex_)].datasetId)) structures_ = std::move(*list);
  }
  return {};
}

std::string LessonController::displayName(const std::string& structureId) const {
  for (const Structure& st : structures_)
    if (st.id == structureId) return st.displayName.empty() ? st.id : st.displayName;
  return structureId;
}

void LessonController::report(const std::string& text) {
  message_ = text;
  std::fprintf(stderr, "anatomy-tutor: %s\n", text.c_str());
}

Result<quiz::KeyComputer*> LessonController::keysFor(const std::string& datasetId) {
  auto list = session_.structures(datasetId);
  if (!list) return tl::unexpected(list.error());
  structures_ = std::move(*list);
  return session_.keysFor(datasetId);
}

// ---------------------------------------------------------------------------------------------
// Running a lesson

std::optional<std::string> LessonController::preparing() const {
  if (!pending_) return std::nullopt;
  return pending_->title;
}

Status LessonController::startLesson(const std::string& lessonId, lessons::LessonMode mode) {
  if (pending_) return fail("another lesson is being prepared");
  if (auto st = ready(); !st) return st;
  auto lesson = session_.curriculum().lesson(lessonId);
  if (!lesson) return tl::unexpected(lesson.error());
  auto course = session_.curriculum().course(lesson->courseId);
  if (!course) return tl::unexpected(course.error());
  if (auto keys = keysFor(course->datasetId); !keys) return tl::unexpected(keys.error());
  auto engine = session_.engineFor(lessonId);
  if (!engine) return tl::unexpected(engine.error());
  // LessonEngine::start computes the answer keys (distance fields: seconds on a large dataset)
  // on a thread of its own; until it is done the controller leaves the session alone.
  Pending pending;
  pending.engine = std::move(*engine);
  pending.lessonId = lessonId;
  pending.courseId = course->id;
  pending.title = lesson->title;
  lessons::LessonEngine* started = pending.engine.get();
  auto stored = storedUserId();
  if (!stored) return tl::unexpected(stored.error());
  const std::int64_t userId = *stored;
  pending.started = std::async(std::launch::async, [started, userId, lessonId, mode] {
    return started->start(userId, lessonId, mode);
  });
  pending_ = std::move(pending);
  startResult_.reset();
  step_.reset();
  asked_.reset();
  finishedScore_.reset();
  return {};
}

void LessonController::poll() {
  if (!pending_ || pending_->started.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  startResult_ = completeStart();
  if (!*startResult_) report(startResult_->error().message);
}

std::optional<Status> LessonController::takeStartResult() {
  if (pending_) return std::nullopt;
  return std::exchange(startResult_, std::nullopt).value_or(Status{});
}

Status LessonController::completeStart() {
  Pending pending = std::move(*pending_);
  pending_.reset();
  Status started = pending.started.get();
  if (!started) {
    events_({{"event", "lesson_refused"}, {"lesson", pending.lessonId}, {"message", started.error().message}});
    return started;
  }
  engine_ = std::move(pending.engine);
  for (int i = 0; i < int(courses_.size()); ++i)
    if (courses_[std::size_t(i)].id == pending.courseId && i != courseIndex_)
      if (auto r = selectCourse(i); !r) return r;
  runningLesson_ = pending.lessonId;
  finishedScore_.reset();
  review_.clear();
  message_.clear();
  const lessons::Attempt& attempt = engine_->attempt();
  events_({{"event", "lesson_started"}, {"lesson", pending.lessonId}, {"course", pending.courseId}, {"user", user_->name},
           {"attempt", attempt.id}, {"resumed", engine_->resumed()}, {"mode", lessons::toString(attempt.mode)}});
  // Resumed after its last question was answered but before it was finished: finish it now.
  return engine_->atEnd() ? finishLesson() : showCurrent();
}

Status LessonController::showCurrent() {
  auto view = engine_->current();
  if (!view) return tl::unexpected(view.error());
  step_ = *view;
  asked_.reset();
  json e = {{"event", "lesson_step"}, {"lesson", runningLesson_}, {"position", view->position},
            {"count", view->count}, {"kind", lessons::toString(view->kind)}};
  if (view->kind == lessons::StepKind::Show) {
    show_({view->structure, view->presetId, view->view, view->scene.camera, view->scene.clip, {}, false});
    e["structure"] = view->structure;
  } else {
    auto question = engine_->currentQuestion();
    if (!question) return tl::unexpected(question.error());
    Asked asked;
    asked.question = std::move(*question);
    asked.choiceNames = view->choiceNames;
    asked.grade = view->feedback;  // resumed: answered before
    // The question's scene (lessons::sceneFor): identify and name questions highlight their
    // target; a locate question shows its region, a neighbouring landmark, without marking it.
    show_({view->scene.structure, view->scene.presetId, view->scene.view, view->scene.camera, view->scene.clip,
           locateTarget(asked.question), false});
    asked_ = std::move(asked);
    e["question"] = view->questionId;
    e["question_kind"] = quiz::toString(view->questionKind);
    e["choices"] = view->choiceIds;
    e["answered"] = view->feedback.has_value();
  }
  events_(e);
  return {};
}

Status LessonController::next() {
  if (!engine_ || !step_) return fail("no lesson is running");
  if (auto st = engine_->next(); !st) return st;
  return engine_->atEnd() ? finishLesson() : showCurrent();
}

Status LessonController::finishLesson() {
  auto score = engine_->finish();
  if (!score) return tl::unexpected(score.error());
  finishedScore_ = *score;
  review_ = engine_->outcomes();
  step_.reset();
  asked_.reset();
  events_({{"event", "lesson_finished"}, {"lesson", runningLesson_}, {"score", *score}});
  return refresh();
}

void LessonController::leave() {
  step_.reset();
  asked_.reset();
  finishedScore_.reset();
  review_.clear();
  engine_.reset();
  if (user_)
    if (auto st = refresh(); !st) report(st.error().message);
}

void LessonController::backToLessons() {
  finishedScore_.reset();
  review_.clear();
  engine_.reset();
}

// ---------------------------------------------------------------------------------------------
// Answers

bool LessonController::wantsClick() const {
  return asked_ && !asked_->grade && asked_->question.question.kind == quiz::QuestionKind::Locate;
}

bool LessonController::wantsClickDistance() const { return wantsClick() && asked_->question.question.toleranceMm > 0; }

bool LessonController::namesHidden() const {
  if (step_ && !step_->labelsVisible) return true;
  return asked_ && !asked_->grade && namesGiveAway(asked_->question.question.kind);
}

std::optional<std::string> LessonController::questionTarget() const {
  if (!asked_) return std::nullopt;
  return asked_->question.question.target;
}

Result<quiz::Grade> LessonController::answer(const quiz::Answer& answer) {
  if (!asked_) return fail("no question is asked");
  if (asked_->grade) return fail("this question is already answered");
  Result<quiz::Grade> grade = fail("no lesson is running");
  const auto latency = std::chrono::duration_cast<std::chrono::milliseconds>(SteadyClock::now() - asked_->shownAt);
  if (asked_->review && reviewSession_) {
    // Graded as a lesson answer and recorded with the structure's progress and Elo, so the
    // review queue moves.
    grade = reviewSession_->answer(answer, renderState_(), latency.count());
  } else if (engine_) {
    grade = engine_->answer(answer, renderState_(), latency.count());
  }
  if (!grade) return grade;
  asked_->grade = *grade;
  // The inputs show the answer given (also one given by a script).
  if (answer.choice) asked_->choice = *answer.choice;
  if (answer.text) asked_->text = *answer.text;
  if (answer.order) asked_->order = *answer.order;
  asked_->keptAsPractice = answersGoToClass_ && answer.pick && !classServerGrades(*answer.pick);
  json e = {{"event", "graded"},       {"question", asked_->question.question.id},
            {"kind", quiz::toString(asked_->question.question.kind)},
            {"answer", json::parse(quiz::answerToJson(answer), nullptr, false)},
            {"correct", grade->correct}, {"score", grade->score},
            {"feedback", grade->feedback}, {"review", asked_->review},
            {"recorded", true}};  // graded means committed: answer() and answerReview() store first
  if (answer.pick) e["clicked"] = answer.pick->structure;
  if (asked_->keptAsPractice) e["class_practice"] = true;
  events_(e);
  if (auto st = refresh(); !st) report(st.error().message);
  return grade;
}

bool LessonController::clicked(const std::string& structure, double distanceMm) {
  if (!wantsClick()) return false;
  quiz::Answer a;
  a.pick = quiz::Pick{structure, distanceMm, std::nullopt, ""};  // a free view: no pixel a server could grade
  if (auto grade = answer(a); !grade) report("answer: " + grade.error().message);
  return true;
}

// ---------------------------------------------------------------------------------------------
// Review

Status LessonController::startReview() {
  if (auto st = ready(); !st) return st;
  if (step_) return fail("finish or leave the running lesson first");
  finishedScore_.reset();
  if (courses_.empty()) return fail("no course to review");
  const lessons::Course& course = courses_[std::size_t(courseIndex_)];
  auto keys = keysFor(course.datasetId);  // also the structures' display names
  if (!keys) return tl::unexpected(keys.error());
  auto session = std::make_unique<lessons::ReviewSession>(session_.curriculum(), session_.progress(), **keys, course, user_->id);
  auto question = session->next();
  if (!question) return tl::unexpected(question.error());
  if (!*question) {
    asked_.reset();
    reviewSession_.reset();
    message_ = "Nothing is due for review in this course.";
    events_({{"event", "review_question"}, {"course", course.id}, {"question", nullptr}});
    return {};
  }
  Asked asked;
  asked.question = (*question)->question;
  asked.review = true;
  for (const std::string& id : asked.question.choices) asked.choiceNames.push_back(displayName(id));
  const quiz::QuestionKind kind = asked.question.question.kind;
  const lessons::QuestionScene& scene = (*question)->scene;
  show_({scene.structure, scene.presetId, scene.view, scene.camera, scene.clip, locateTarget(asked.question), false});
  events_({{"event", "review_question"}, {"course", course.id}, {"question", asked.question.question.id},
           {"question_kind", quiz::toString(kind)}, {"target", asked.question.question.target},
           {"choices", asked.question.choices}});
  asked_ = std::move(asked);
  reviewSession_ = std::move(session);
  message_.clear();
  return {};
}

void LessonController::dismissReview() {
  if (asked_ && asked_->review) asked_.reset();
  reviewSession_.reset();
}

}  // namespace at::app
