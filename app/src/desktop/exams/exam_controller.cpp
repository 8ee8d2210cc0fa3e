// [SECTIONS] lists · starting · items and answers · the end
#include "exams/exam_controller.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <set>

namespace at::app {

namespace {
using json = nlohmann::json;
using SteadyClock = std::chrono::steady_clock;
}  // namespace

ExamController::ExamController(LearningSession& session, LessonController& lessons, EventSink events, ShowItem show,
                               RenderStateSource renderState)
    : learning_(session),
      lessons_(lessons),
      events_(std::move(events)),
      show_(std::move(show)),
      renderState_(std::move(renderState)),
      repository_(session.database()) {}

ExamController::~ExamController() = default;

// ---------------------------------------------------------------------------------------------
// Lists

namespace {
std::string rowsKey(const LessonController& lessons) {
  if (!lessons.user() || lessons.courses().empty()) return "";
  std::string key = std::to_string(lessons.user()->id) + "/" + lessons.courses()[std::size_t(lessons.courseIndex())].id;
  for (const LessonController::LessonRow& row : lessons.rows()) key += row.bestScore ? "/" + row.id : "";
  return key;
}
}  // namespace

Status ExamController::sync() {
  if (auto st = lessons_.ready(); !st) return st;
  if (rowsKey(lessons_) == rowsKey_) return {};
  return refresh();
}

Status ExamController::refresh() {
  rows_.clear();
  if (auto st = lessons_.ready(); !st) return st;
  rowsKey_ = rowsKey(lessons_);
  const auto& courses = lessons_.courses();
  if (courses.empty()) return {};
  const lessons::Course& course = courses[std::size_t(lessons_.courseIndex())];
  auto attempts = repository_.examAttempts(lessons_.user()->id);  // newest first
  if (!attempts) return tl::unexpected(attempts.error());
  std::map<std::string, std::string> titles;  // prerequisites may lie in another course
  for (const lessons::Course& c : courses)
    for (const lessons::Lesson& l : c.lessons) titles[l.id] = l.title;
  std::set<std::string> finished;
  auto lessonAttempts = learning_.progress().attempts(lessons_.user()->id);
  if (!lessonAttempts) return tl::unexpected(lessonAttempts.error());
  for (const lessons::Attempt& a : *lessonAttempts)
    if (a.finishedAt) finished.insert(a.lessonId);
  for (const lessons::ExamSpec& exam : course.exams) {
    ExamRow row;
    row.id = exam.id;
    row.title = exam.title;
    row.instructions = exam.instructions;
    row.count = exam.count;
    row.timeLimitS = exam.timeLimitS;
    row.passScore = exam.passScore;
    for (const std::string& pre : exam.prerequisites)
      if (!finished.count(pre)) row.missing.push_back(titles.count(pre) ? titles[pre] : pre);
    for (const lessons::ExamAttempt& a : *attempts)
      if (a.examId == exam.id) {
        row.latest = a;
        break;
      }
    rows_.push_back(std::move(row));
  }
  return {};
}

std::string ExamController::displayName(const std::string& structureId) const {
  for (const Structure& s : structures_)
    if (s.id == structureId) return s.displayName.empty() ? s.id : s.displayName;
  return structureId;
}

// ---------------------------------------------------------------------------------------------
// Starting

std::optional<std::string> ExamController::preparing() const {
  if (!pending_) return std::nullopt;
  return pending_->title;
}

Status ExamController::start(const std::string& examId) {
  if (pending_) return fail("an exam is being prepared");
  if (running()) return fail("an exam is running: hand it in or leave it first");
  if (lessons_.preparing() || lessons_.step()) return fail("leave the running lesson before starting an exam");
  if (auto st = lessons_.ready(); !st) return st;
  auto found = lessons::findExam(learning_.curriculum(), examId);
  if (!found) return tl::unexpected(found.error());
  const std::string datasetId = found->first.datasetId;
  auto structures = learning_.structures(datasetId);
  if (!structures) return tl::unexpected(structures.error());
  auto keys = learning_.keysFor(datasetId);
  if (!keys) return tl::unexpected(keys.error());
  structures_ = std::move(*structures);
  result_.reset();
  item_.reset();
  session_ = std::make_unique<lessons::ExamSession>(learning_.curriculum(), learning_.progress(), repository_, **keys);
  // ExamSession::start draws the items from the answer keys (distance fields: seconds on a large
  // dataset) on a thread of its own; until it is done nothing else touches the session.
  lessons::ExamSession* started = session_.get();
  auto stored = lessons_.storedUserId();
  if (!stored) return tl::unexpected(stored.error());
  const std::int64_t userId = *stored;
  Pending pending;
  pending.examId = examId;
  pending.title = found->second.title;
  pending.started = std::async(std::launch::async, [started, userId, examId] { return started->start(userId, examId); });
  pending_ = std::move(pending);
  startResult_.reset();
  return {};
}

void ExamController::poll() {
  if (pending_) {
    if (pending_->started.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
    startResult_ = completeStart();
    if (!*startResult_) lessons_.report("exam: " + startResult_->error().message);
    return;
  }
  if (running() && session_->secondsLeft() <= 0)
    if (auto st = finish(); !st) lessons_.report("exam: " + st.error().message);
}

std::optional<Status> ExamController::takeStartResult() {
  if (pending_) return std::nullopt;
  return std::exchange(startResult_, std::nullopt).value_or(Status{});
}

Status ExamController::completeStart() {
  Pending pending = std::move(*pending_);
  pending_.reset();
  if (Status started = pending.started.get(); !started) {
    session_.reset();
    events_({{"event", "exam_refused"}, {"exam", pending.examId}, {"message", started.error().message}});
    return started;
  }
  events_({{"event", "exam_started"}, {"exam", pending.examId}, {"attempt", session_->attempt().id},
           {"items", session_->itemCount()}, {"resumed", session_->resumed()},
           {"seconds_left", session_->secondsLeft()}});
  // Resumed past its deadline: handed in with what was answered.
  if (session_->secondsLeft() <= 0) return finish();
  return show(session_->nextUnanswered().value_or(0));
}

// ---------------------------------------------------------------------------------------------
// Items and answers

int ExamController::answeredCount() const {
  int n = 0;
  for (int i = 0; i < itemCount(); ++i) n += itemAnswered(i) ? 1 : 0;
  return n;
}

bool ExamController::itemAnswered(int i) const {
  if (!session_ || pending_) return false;
  auto v = session_->item(i);
  return v && v->answered;
}

Status ExamController::show(int position) {
  auto view = session_->item(position);
  if (!view) return tl::unexpected(view.error());
  position_ = position;
  item_ = *view;
  choice = -1;
  text.clear();
  shownAt_ = SteadyClock::now();
  const bool locate = view->kind == quiz::QuestionKind::Locate;
  show_(ItemScene{view->scene, view->target, locate, locate && view->locateView == lessons::ExamLocateView::Slice,
                  false});
  json e = {{"event", "exam_item"}, {"exam", session_->exam().id}, {"position", position}, {"count", view->count},
            {"kind", quiz::toString(view->kind)}, {"prompt", view->prompt}, {"answered", view->answered},
            {"seconds_left", session_->secondsLeft()}};
  if (locate) e["locate_view"] = lessons::toString(view->locateView);
  if (!view->choiceNames.empty()) e["choices"] = view->choiceNames;
  events_(e);
  return {};
}

Status ExamController::goTo(int position) {
  if (!running()) return fail("no exam is running");
  return show(position);
}

bool ExamController::wantsClick() const {
  return running() && item_ && !item_->answered && item_->kind == quiz::QuestionKind::Locate &&
         item_->locateView == lessons::ExamLocateView::ThreeD;
}

bool ExamController::wantsSliceClick() const {
  return running() && item_ && !item_->answered && item_->kind == quiz::QuestionKind::Locate &&
         item_->locateView == lessons::ExamLocateView::Slice;
}

std::optional<std::string> ExamController::itemTarget() const {
  if (!running() || !item_) return std::nullopt;
  return item_->target;
}

bool ExamController::acceptsClickDistance() const {
  if (!running() || !item_) return false;
  auto q = session_->itemQuestion(position_);
  return q && q->question.toleranceMm > 0;
}

Status ExamController::answer(const quiz::Answer& given) {
  if (!running() || !item_) return fail("no exam item is on screen");
  if (item_->answered) return fail("exam item " + std::to_string(position_ + 1) + " is already answered");
  const auto latency = std::chrono::duration_cast<std::chrono::milliseconds>(SteadyClock::now() - shownAt_);
  lessons::RenderState render = renderState_();
  render.mode = item_->kind == quiz::QuestionKind::Locate && item_->locateView == lessons::ExamLocateView::Slice
                    ? "slice" : render.mode;
  if (auto st = session_->answer(position_, given, latency.count(), render); !st) {
    if (session_->secondsLeft() <= 0) {  // too late: hand in what was answered before
      if (auto handed = finish(); !handed) return handed;
    }
    return st;
  }
  item_->answered = true;
  events_({{"event", "exam_answered"}, {"exam", session_->exam().id}, {"position", position_},
           {"answered", answeredCount()}, {"count", itemCount()}});
  // On to the next unanswered item after this one (wrapping); stay when every item is answered.
  for (int step = 1; step < itemCount(); ++step) {
    const int next = (position_ + step) % itemCount();
    if (!itemAnswered(next)) return show(next);
  }
  return {};
}

bool ExamController::clicked(const std::string& structure, double distanceMm) {
  if (!wantsClick() && !wantsSliceClick()) return false;
  quiz::Answer a;
  a.pick = quiz::Pick{};
  a.pick->structure = structure;
  a.pick->distanceMm = distanceMm;
  if (auto st = answer(a); !st) lessons_.report("exam: " + st.error().message);
  return true;
}

// ---------------------------------------------------------------------------------------------
// The end

Status ExamController::finish() {
  if (!running()) return fail("no exam is running");
  auto result = session_->finish();
  if (!result) return tl::unexpected(result.error());
  finished(*result);
  return {};
}

void ExamController::finished(const lessons::ExamResult& r) {
  result_ = r;
  item_.reset();
  show_(std::nullopt);
  json items = json::array();
  for (const lessons::ExamItemResult& x : r.items)
    items.push_back({{"position", x.position}, {"structure", x.structure}, {"kind", quiz::toString(x.kind)},
                     {"answered", x.answered}, {"correct", x.correct}, {"score", x.score}, {"feedback", x.feedback},
                     {"your_answer", x.yourAnswer}, {"right_answer", x.rightAnswer}});
  json e = {{"event", "exam_finished"}, {"exam", session_->exam().id}, {"score", r.score}, {"answered", r.answered},
            {"correct", r.correct}, {"time_ran_out", r.timeRanOut}, {"items", items}};
  e["passed"] = r.passed ? json(*r.passed) : json(nullptr);
  events_(e);
  if (auto st = refresh(); !st) lessons_.report("exam: " + st.error().message);
}

void ExamController::leave() {
  if (!running()) return;
  events_({{"event", "exam_left"}, {"exam", session_->exam().id}, {"answered", answeredCount()},
           {"seconds_left", session_->secondsLeft()}});
  session_.reset();
  item_.reset();
  show_(std::nullopt);
  if (auto st = refresh(); !st) lessons_.report("exam: " + st.error().message);
}

void ExamController::closeResults() {
  result_.reset();
  session_.reset();
  show_(std::nullopt);
}

Status ExamController::showResultItem(int index, bool onSlice) {
  if (!result_) return fail("no exam results to review: hand the exam in first");
  if (index < 0 || index >= int(result_->items.size()))
    return fail("the exam review has items 0.." + std::to_string(int(result_->items.size()) - 1) + ", not " +
                std::to_string(index));
  const lessons::ExamItemResult& x = result_->items[std::size_t(index)];
  ItemScene scene{x.scene, x.structure, false, false, onSlice};
  show_(scene);
  events_({{"event", "exam_review_item"}, {"index", index}, {"structure", x.structure}, {"preset", x.scene.presetId},
           {"view", lessons::toString(x.scene.view)}, {"slice", onSlice}, {"answered", x.answered},
           {"correct", x.correct}, {"your_answer", x.yourAnswer}, {"right_answer", x.rightAnswer}});
  return {};
}

}  // namespace at::app
