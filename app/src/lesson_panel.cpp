// [SECTIONS] store and lists · running a lesson · answers · review · drawing · scripted actions
#include "lesson_panel.h"

#include <algorithm>
#include <cstdio>
#include <ctime>
#include <map>
#include <set>

#include <imgui.h>

#include "quiz/answer_json.h"
#include "quiz/grading.h"
#include "quiz/keys.h"
#include "volume/dataset_source.h"

namespace at::app {

namespace {

using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

lessons::UnixSeconds unixNow() { return lessons::UnixSeconds(std::time(nullptr)); }

// Questions whose answer a visible structure name would give away while unanswered.
bool namesGiveAway(quiz::QuestionKind kind) {
  return kind == quiz::QuestionKind::Locate || kind == quiz::QuestionKind::Identify || kind == quiz::QuestionKind::Name;
}

const ImVec4 kRight{0.5f, 1, 0.5f, 1}, kWrong{1, 0.5f, 0.4f, 1}, kHeading{1, 0.75f, 0.3f, 1}, kQuestion{0.6f, 0.8f, 1, 1};

}  // namespace

// ---------------------------------------------------------------------------------------------
// Store and lists

// The panel's learner state over the session: the user, the running lesson's engine and the
// structures of the course being taught (for display names).
struct LessonPanel::Store {
  LearningSession& session;
  lessons::CurriculumRepository& curriculum;
  lessons::ProgressRepository& progress;
  lessons::User user;
  std::vector<Structure> structures;        // of the course dataset last asked for
  std::unique_ptr<lessons::LessonEngine> engine;
  lessons::Course reviewCourse;             // the course of the review question (synonyms)

  explicit Store(LearningSession& s) : session(s), curriculum(s.curriculum()), progress(s.progress()) {}

  // The answer keys of `datasetId` (the course's dataset, loaded only when a key needs it).
  Result<quiz::KeyComputer*> keysFor(const std::string& datasetId) {
    auto list = session.structures(datasetId);
    if (!list) return tl::unexpected(list.error());
    structures = std::move(*list);
    return session.keysFor(datasetId);
  }
};

LessonPanel::LessonPanel(LearningSession& session, std::string userName, std::string viewDataset,
                         EventSink events, ShowStructure show, RenderStateSource renderState)
    : session_(session),
      userName_(std::move(userName)),
      viewDataset_(std::move(viewDataset)),
      events_(std::move(events)),
      show_(std::move(show)),
      renderState_(std::move(renderState)) {}

LessonPanel::~LessonPanel() = default;

Result<LessonPanel::Store*> LessonPanel::store() {
  if (store_) return store_.get();
  if (!storeError_.empty()) return at::fail(storeError_);  // opened once and failed: not retried per frame
  auto s = std::make_unique<Store>(session_);
  auto user = session_.user(userName_, LearningSession::NewUser::Create);
  if (!user) return at::fail(storeError_ = "lessons: " + user.error().message);
  s->user = *user;
  std::snprintf(userEdit_, sizeof userEdit_, "%s", s->user.name.c_str());
  store_ = std::move(s);
  if (auto st = refresh(); !st) return tl::unexpected(st.error());
  return store_.get();
}

Status LessonPanel::switchUser(const std::string& name) {
  if (step_) return at::fail("leave the running lesson before changing the user");
  if (name.empty()) return at::fail("type a user name (a pseudonym)");
  auto s = store();
  if (!s) return tl::unexpected(s.error());
  auto user = session_.user(name, LearningSession::NewUser::Create);
  if (!user) return tl::unexpected(user.error());
  (*s)->user = *user;
  userName_ = name;
  std::snprintf(userEdit_, sizeof userEdit_, "%s", name.c_str());
  asked_.reset();
  finishedScore_.reset();
  (*s)->engine.reset();
  message_.clear();
  events_({{"event", "lesson_user"}, {"user", user->name}, {"id", user->id}});
  return refresh();
}

Status LessonPanel::refresh() {
  Store& s = *store_;
  auto courses = s.curriculum.courses();
  if (!courses) return tl::unexpected(courses.error());
  courses_ = std::move(*courses);
  courseIndex_ = std::clamp(courseIndex_, 0, std::max(0, int(courses_.size()) - 1));
  auto attempts = s.progress.attempts(s.user.id);
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
    auto due = lessons::reviewQueue(s.curriculum, s.progress, s.user.id, courses_[std::size_t(courseIndex_)].id, unixNow());
    if (!due) return tl::unexpected(due.error());
    due_ = std::move(*due);
  }
  return {};
}

std::string LessonPanel::displayName(const std::string& structureId) const {
  if (store_)
    for (const Structure& st : store_->structures)
      if (st.id == structureId) return st.displayName.empty() ? st.id : st.displayName;
  return structureId;
}

void LessonPanel::fail(const std::string& text) {
  message_ = text;
  std::fprintf(stderr, "anatomy-tutor: %s\n", text.c_str());
}

// ---------------------------------------------------------------------------------------------
// Running a lesson

Status LessonPanel::startLesson(const std::string& lessonId, lessons::LessonMode mode) {
  if (pending_) return at::fail("another lesson is being prepared");
  auto s = store();
  if (!s) return tl::unexpected(s.error());
  Store& st = **s;
  auto lesson = st.curriculum.lesson(lessonId);
  if (!lesson) return tl::unexpected(lesson.error());
  auto course = st.curriculum.course(lesson->courseId);
  if (!course) return tl::unexpected(course.error());
  auto keys = st.keysFor(course->datasetId);  // and the structures' display names
  if (!keys) return tl::unexpected(keys.error());
  auto madeEngine = session_.engineFor(lessonId);
  if (!madeEngine) return tl::unexpected(madeEngine.error());
  // LessonEngine::start computes the answer keys (distance fields: seconds on a large dataset)
  // on a thread of its own; until it is done the panel does not touch the store.
  Pending pending;
  pending.engine = std::move(*madeEngine);
  pending.lessonId = lessonId;
  pending.courseId = course->id;
  pending.title = lesson->title;
  lessons::LessonEngine* engine = pending.engine.get();
  const std::int64_t userId = st.user.id;
  pending.started = std::async(std::launch::async, [engine, userId, lessonId, mode] {
    return engine->start(userId, lessonId, mode);
  });
  pending_ = std::move(pending);
  startResult_.reset();
  step_.reset();
  asked_.reset();
  finishedScore_.reset();
  return {};
}

void LessonPanel::pollStart() {
  if (!pending_ || pending_->started.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return;
  startResult_ = completeStart();
  if (!*startResult_) fail(startResult_->error().message);
}

Status LessonPanel::completeStart() {
  Pending pending = std::move(*pending_);
  pending_.reset();
  Status started = pending.started.get();
  if (!started) {
    events_({{"event", "lesson_refused"}, {"lesson", pending.lessonId}, {"message", started.error().message}});
    return started;
  }
  Store& st = *store_;
  const std::string lessonId = pending.lessonId;
  st.engine = std::move(pending.engine);
  for (int i = 0; i < int(courses_.size()); ++i)
    if (courses_[std::size_t(i)].id == pending.courseId && i != courseIndex_) {
      courseIndex_ = i;
      if (auto r = refresh(); !r) return r;
    }
  runningLesson_ = lessonId;
  finishedScore_.reset();
  message_.clear();
  const lessons::Attempt& attempt = st.engine->attempt();
  events_({{"event", "lesson_started"}, {"lesson", lessonId}, {"course", pending.courseId}, {"user", st.user.name},
           {"attempt", attempt.id}, {"resumed", st.engine->resumed()}, {"mode", lessons::toString(attempt.mode)}});
  // Resumed after its last question was answered but before it was finished: finish it now.
  return st.engine->atEnd() ? finishLesson() : showCurrent();
}

Status LessonPanel::showCurrent() {
  lessons::LessonEngine& engine = *store_->engine;
  auto view = engine.current();
  if (!view) return tl::unexpected(view.error());
  step_ = *view;
  asked_.reset();
  json e = {{"event", "lesson_step"}, {"lesson", runningLesson_}, {"position", view->position},
            {"count", view->count}, {"kind", lessons::toString(view->kind)}};
  if (view->kind == lessons::StepKind::Show) {
    show_({view->structure, view->presetId, view->view});
    e["structure"] = view->structure;
  } else {
    auto question = engine.currentQuestion();
    if (!question) return tl::unexpected(question.error());
    Asked asked;
    asked.question = std::move(*question);
    asked.choiceNames = view->choiceNames;
    asked.grade = view->feedback;  // resumed: answered before
    const quiz::QuestionKind kind = view->questionKind;
    // Identify and name questions ask about a highlighted structure; a relation question about
    // the structure the distances are measured from. Locate and order questions keep the view.
    if (kind == quiz::QuestionKind::Identify || kind == quiz::QuestionKind::Name ||
        kind == quiz::QuestionKind::Relation)
      show_({asked.question.question.target, "", std::nullopt});
    asked_ = std::move(asked);
    e["question"] = view->questionId;
    e["question_kind"] = quiz::toString(kind);
    e["choices"] = view->choiceIds;
    e["answered"] = view->feedback.has_value();
  }
  events_(e);
  return {};
}

Status LessonPanel::nextStep() {
  if (!store_ || !store_->engine || !step_) return at::fail("no lesson is running");
  lessons::LessonEngine& engine = *store_->engine;
  if (auto st = engine.next(); !st) return st;
  return engine.atEnd() ? finishLesson() : showCurrent();
}

Status LessonPanel::finishLesson() {
  auto score = store_->engine->finish();
  if (!score) return tl::unexpected(score.error());
  finishedScore_ = *score;
  step_.reset();
  asked_.reset();
  events_({{"event", "lesson_finished"}, {"lesson", runningLesson_}, {"score", *score}});
  return refresh();
}

// ---------------------------------------------------------------------------------------------
// Answers

bool LessonPanel::wantsClick() const {
  return asked_ && !asked_->grade && asked_->question.question.kind == quiz::QuestionKind::Locate;
}

bool LessonPanel::wantsClickDistance() const {
  return wantsClick() && asked_->question.question.toleranceMm > 0;
}

bool LessonPanel::namesHidden() const {
  if (step_ && !step_->labelsVisible) return true;
  return asked_ && !asked_->grade && namesGiveAway(asked_->question.question.kind);
}

std::optional<std::string> LessonPanel::questionTarget() const {
  if (!asked_) return std::nullopt;
  return asked_->question.question.target;
}

Result<quiz::Grade> LessonPanel::submit(const quiz::Answer& answer) {
  if (!asked_) return at::fail("no question is asked");
  if (asked_->grade) return at::fail("this question is already answered");
  Result<quiz::Grade> grade = at::fail("no lesson is running");
  const auto latency = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - asked_->shownAt);
  if (asked_->review && store_) {
    // Graded as a lesson answer and recorded with the structure's progress and Elo, so the
    // review queue moves.
    auto keys = store_->keysFor(store_->reviewCourse.datasetId);
    if (!keys) return tl::unexpected(keys.error());
    lessons::ReviewAnswer review;
    review.userId = store_->user.id;
    review.courseId = store_->reviewCourse.id;
    review.question = asked_->question.question;
    review.answer = answer;
    review.render = renderState_();
    review.latencyMs = latency.count();
    grade = lessons::answerReview(store_->curriculum, store_->progress, **keys, review);
  } else if (store_ && store_->engine) {
    grade = store_->engine->answer(answer, renderState_(), latency.count());
  }
  if (!grade) return grade;
  asked_->grade = *grade;
  // The inputs show the answer given (also one given by a script).
  if (answer.choice) asked_->choice = *answer.choice;
  if (answer.text) asked_->text = *answer.text;
  if (answer.order) asked_->order = *answer.order;
  json e = {{"event", "graded"},       {"question", asked_->question.question.id},
            {"kind", quiz::toString(asked_->question.question.kind)},
            {"answer", json::parse(quiz::answerToJson(answer), nullptr, false)},
            {"correct", grade->correct}, {"score", grade->score},
            {"feedback", grade->feedback}, {"review", asked_->review},
            {"recorded", true}};  // graded means committed: answer() and answerReview() store first
  if (answer.pick) e["clicked"] = answer.pick->structure;
  events_(e);
  if (auto st = refresh(); !st) fail(st.error().message);
  return grade;
}

bool LessonPanel::clicked(const std::string& structure, double distanceMm) {
  if (!wantsClick()) return false;
  quiz::Answer answer;
  answer.pick = quiz::Pick{structure, distanceMm};
  if (auto grade = submit(answer); !grade) fail("answer: " + grade.error().message);
  return true;
}

// ---------------------------------------------------------------------------------------------
// Review

Status LessonPanel::startReview() {
  auto s = store();
  if (!s) return tl::unexpected(s.error());
  Store& st = **s;
  if (step_) return at::fail("finish or leave the running lesson first");
  finishedScore_.reset();
  if (courses_.empty()) return at::fail("no course to review");
  const lessons::Course& course = courses_[std::size_t(courseIndex_)];
  auto question = lessons::chooseReviewQuestion(st.curriculum, st.progress, st.user.id, course.id, unixNow());
  if (!question) return tl::unexpected(question.error());
  if (!*question) {
    asked_.reset();
    message_ = "Nothing is due for review in this course.";
    events_({{"event", "review_question"}, {"course", course.id}, {"question", nullptr}});
    return {};
  }
  auto keys = st.keysFor(course.datasetId);
  if (!keys) return tl::unexpected(keys.error());
  auto resolved = quiz::resolveQuestion(**question, **keys);
  if (!resolved) return tl::unexpected(resolved.error());
  st.reviewCourse = course;
  Asked asked;
  asked.question = std::move(*resolved);
  asked.review = true;
  for (const std::string& id : asked.question.choices) asked.choiceNames.push_back(displayName(id));
  const quiz::QuestionKind kind = asked.question.question.kind;
  if (kind == quiz::QuestionKind::Identify || kind == quiz::QuestionKind::Name || kind == quiz::QuestionKind::Relation)
    show_({asked.question.question.target, "", std::nullopt});
  events_({{"event", "review_question"}, {"course", course.id}, {"question", asked.question.question.id},
           {"question_kind", quiz::toString(kind)}, {"target", asked.question.question.target},
           {"choices", asked.question.choices}});
  asked_ = std::move(asked);
  message_.clear();
  return {};
}

// ---------------------------------------------------------------------------------------------
// Drawing

void LessonPanel::draw(float height) {
  if (!ImGui::CollapsingHeader("Lessons", ImGuiTreeNodeFlags_DefaultOpen)) return;
  ImGui::BeginChild("lessons", ImVec2(0, height), false);
  drawContent();
  ImGui::EndChild();
}

void LessonPanel::drawContent() {
  pollStart();
  if (pending_) {
    ImGui::TextColored(kHeading, "%s", pending_->title.c_str());
    ImGui::TextDisabled("Preparing the lesson: computing its answer keys...");
    return;
  }
  auto s = store();
  if (!s) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(kWrong, "%s", s.error().message.c_str());
    ImGui::PopTextWrapPos();
    return;
  }
  if (step_) {
    ImGui::TextDisabled("user: %s", (*s)->user.name.c_str());
  } else {
    ImGui::SetNextItemWidth(ImGui::GetFontSize() * 9);
    const bool entered = ImGui::InputText("##user", userEdit_, sizeof userEdit_, ImGuiInputTextFlags_EnterReturnsTrue);
    ImGui::SameLine();
    if ((ImGui::SmallButton("switch user") || entered) && userEdit_ != (*s)->user.name)
      if (auto st = switchUser(userEdit_); !st) fail("user: " + st.error().message);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("progress is per user; `anatomy-tutor play --user NAME` shares it");
  }
  if (step_ || finishedScore_) drawLesson();
  else if (asked_ && asked_->review) drawQuestion();
  else drawCourses();
  if (!message_.empty()) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(kWrong, "%s", message_.c_str());
    ImGui::PopTextWrapPos();
  }
  if (!step_ && !finishedScore_ && !(asked_ && asked_->review)) drawReview();
}

void LessonPanel::drawCourses() {
  if (courses_.empty()) {
    ImGui::TextDisabled("No course in the database.");
    return;
  }
  const lessons::Course& course = courses_[std::size_t(courseIndex_)];
  if (ImGui::BeginCombo("course", course.title.c_str())) {
    for (int i = 0; i < int(courses_.size()); ++i)
      if (ImGui::Selectable(courses_[std::size_t(i)].title.c_str(), i == courseIndex_) && i != courseIndex_) {
        courseIndex_ = i;
        if (auto st = refresh(); !st) fail(st.error().message);
      }
    ImGui::EndCombo();
  }
  // The built-in phantom at any size has the same structures; other datasets only their own.
  if (course.datasetId != viewDataset_ && !(isBuiltinDatasetName(course.datasetId) && isBuiltinDatasetName(viewDataset_))) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(kWrong, "This course is on dataset '%s' but the view shows '%s': open it with --dataset %s.",
                       course.datasetId.c_str(), viewDataset_.c_str(), course.datasetId.c_str());
    ImGui::PopTextWrapPos();
  }
  ImGui::Checkbox("quiz only (no teaching steps, no names)", &modeQuizOnly_);
  ImGui::PushTextWrapPos(0);
  for (const LessonRow& row : rows_) {
    ImGui::PushID(row.id.c_str());
    const bool locked = !row.missing.empty();
    if (locked) ImGui::BeginDisabled();
    const char* action = row.open ? "Resume" : row.bestScore ? "Again" : "Start";
    if (ImGui::SmallButton(action)) {
      if (auto st = startLesson(row.id, modeQuizOnly_ ? lessons::LessonMode::QuizOnly : lessons::LessonMode::Guided); !st)
        fail(st.error().message);
    }
    if (locked) ImGui::EndDisabled();
    ImGui::SameLine();
    ImGui::TextColored(locked ? ImVec4(0.6f, 0.6f, 0.6f, 1) : kHeading, "%s", row.title.c_str());
    if (ImGui::IsItemHovered() && !row.summary.empty()) ImGui::SetTooltip("%s", row.summary.c_str());
    if (locked) {
      std::string needs;
      for (const std::string& m : row.missing) needs += (needs.empty() ? "" : ", ") + m;
      ImGui::TextDisabled("  locked: finish %s first", needs.c_str());
    } else if (row.bestScore) {
      ImGui::TextColored(kRight, "  done, best score %.0f%%%s", 100 * *row.bestScore,
                         row.open ? " (another attempt open)" : "");
    } else if (row.open) {
      ImGui::TextDisabled("  in progress");
    } else {
      ImGui::TextDisabled("  not started, %d questions", row.questions);
    }
    ImGui::PopID();
  }
  ImGui::PopTextWrapPos();
}

void LessonPanel::drawLesson() {
  if (!store_->engine) return;
  lessons::LessonEngine& engine = *store_->engine;
  ImGui::TextColored(kHeading, "%s", engine.lesson().title.c_str());
  if (finishedScore_) {
    ImGui::Text("Lesson finished: score %.0f%%", 100 * *finishedScore_);
    if (ImGui::Button("Back to the lessons")) {
      finishedScore_.reset();
      store_->engine.reset();
    }
    return;
  }
  const lessons::StepView& v = *step_;
  ImGui::Text("step %d of %d", v.position, v.count);
  ImGui::SameLine();
  if (ImGui::SmallButton("Leave")) {  // answers are saved: Resume continues here
    step_.reset();
    asked_.reset();
    store_->engine.reset();
    if (auto st = refresh(); !st) fail(st.error().message);
    return;
  }
  if (v.kind == lessons::StepKind::Show) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(kHeading, "%s", v.title.c_str());
    if (v.labelsVisible && !v.structureName.empty() && v.structureName != v.title)
      ImGui::TextDisabled("%s", v.structureName.c_str());
    ImGui::TextUnformatted(v.text.c_str());
    ImGui::PopTextWrapPos();
  } else {
    drawQuestion();
  }
  const bool canGo = v.kind == lessons::StepKind::Show || (asked_ && asked_->grade);
  if (!canGo) ImGui::BeginDisabled();
  if (ImGui::Button(v.position == v.count ? "Finish" : "Next"))
    if (auto st = nextStep(); !st) fail(st.error().message);
  if (!canGo) ImGui::EndDisabled();
}

void LessonPanel::drawQuestion() {
  if (!asked_) return;
  Asked& a = *asked_;
  const quiz::Question& q = a.question.question;
  ImGui::PushTextWrapPos(0);
  ImGui::TextColored(kQuestion, a.review ? "Review question (%s)" : "Question (%s)", quiz::toString(q.kind));
  ImGui::TextUnformatted(q.prompt.c_str());
  const bool open = !a.grade;
  if (!open) ImGui::BeginDisabled();
  std::optional<quiz::Answer> answer;
  switch (q.kind) {
    case quiz::QuestionKind::Locate:
      ImGui::TextDisabled("Click it in the 3-D view.");
      break;
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation:
      for (int i = 0; i < int(a.choiceNames.size()); ++i) {
        ImGui::PushID(i);
        if (ImGui::RadioButton(a.choiceNames[std::size_t(i)].c_str(), a.choice == i)) a.choice = i;
        ImGui::PopID();
      }
      if (a.choice < 0) ImGui::BeginDisabled();
      if (ImGui::Button("Answer")) (answer = quiz::Answer{})->choice = a.choice;
      if (a.choice < 0) ImGui::EndDisabled();
      break;
    case quiz::QuestionKind::Name: {
      char buffer[128];
      std::snprintf(buffer, sizeof buffer, "%s", a.text.c_str());
      if (ImGui::InputTextWithHint("##name", "type the name", buffer, sizeof buffer)) a.text = buffer;
      if (a.text.empty()) ImGui::BeginDisabled();
      if (ImGui::Button("Answer")) (answer = quiz::Answer{})->text = a.text;
      if (a.text.empty()) ImGui::EndDisabled();
      break;
    }
    case quiz::QuestionKind::Order: {
      ImGui::TextDisabled("Your path, first met first:");
      for (int i = 0; i < int(a.order.size()); ++i) {
        ImGui::PushID(i);
        if (ImGui::ArrowButton("up", ImGuiDir_Up) && i > 0) std::swap(a.order[std::size_t(i)], a.order[std::size_t(i - 1)]);
        ImGui::SameLine();
        if (ImGui::SmallButton("x")) {
          a.order.erase(a.order.begin() + i);
          ImGui::PopID();
          break;
        }
        ImGui::SameLine();
        ImGui::Text("%d. %s", i + 1, displayName(a.order[std::size_t(i)]).c_str());
        ImGui::PopID();
      }
      ImGui::TextDisabled("Offered (click to add):");
      for (std::size_t i = 0; i < a.question.choices.size(); ++i) {
        const std::string& id = a.question.choices[i];
        if (std::find(a.order.begin(), a.order.end(), id) != a.order.end()) continue;
        ImGui::PushID(int(i));
        if (ImGui::SmallButton(a.choiceNames[i].c_str())) a.order.push_back(id);
        ImGui::PopID();
      }
      if (a.order.empty()) ImGui::BeginDisabled();
      if (ImGui::Button("Answer")) (answer = quiz::Answer{})->order = a.order;
      if (a.order.empty()) ImGui::EndDisabled();
      break;
    }
  }
  if (!open) ImGui::EndDisabled();
  if (answer)
    if (auto grade = submit(*answer); !grade) fail("answer: " + grade.error().message);
  if (a.grade) {
    ImGui::TextColored(a.grade->correct ? kRight : kWrong, "%s", a.grade->correct ? "Correct." : "Not quite.");
    ImGui::TextUnformatted(a.grade->feedback.c_str());
    if (a.review) ImGui::TextDisabled("Saved: the review queue is updated.");
  }
  if (a.review && ImGui::Button(a.grade ? "Done" : "Skip")) asked_.reset();
  ImGui::PopTextWrapPos();
}

void LessonPanel::drawReview() {
  ImGui::Separator();
  ImGui::Text("Due for review: %zu", due_.size());
  ImGui::PushTextWrapPos(0);
  std::string list;
  for (const lessons::StructureProgress& p : due_) list += (list.empty() ? "" : ", ") + displayName(p.structureId);
  if (!list.empty()) ImGui::TextDisabled("%s", list.c_str());
  ImGui::PopTextWrapPos();
  if (ImGui::SmallButton("Review"))
    if (auto st = startReview(); !st) fail("review: " + st.error().message);
}

// ---------------------------------------------------------------------------------------------
// Scripted actions

bool LessonPanel::handled(const std::string& what) {
  return what == "lesson_user" || what == "lessons" || what == "lesson" || what == "lesson_next" || what == "answer" || what == "review" || what == "lesson_close";
}

Result<quiz::Answer> LessonPanel::answerFromScript(const json& value) const {
  if (!asked_) return at::fail("no question is asked");
  const quiz::ResolvedQuestion& q = asked_->question;
  quiz::Answer answer;
  if (value.is_object()) return quiz::answerFromJson(value.dump());  // the `play --answers` form
  switch (q.question.kind) {
    case quiz::QuestionKind::Locate:
      return at::fail("a locate question is answered by a click in the view (click, click_structure)");
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation:
      if (value.is_number_integer()) {
        answer.choice = value.get<int>();
      } else if (value.is_string()) {  // the choice labelled so (its id or display name)
        const std::string wanted = value.get<std::string>();
        for (std::size_t i = 0; i < q.choices.size(); ++i)
          if (q.choices[i] == wanted || asked_->choiceNames[i] == wanted) answer.choice = int(i);
        if (!answer.choice) return at::fail("'" + wanted + "' is not one of the choices");
      } else {
        return at::fail("answer a choice question with a number or a choice's id or name");
      }
      break;
    case quiz::QuestionKind::Name:
      if (!value.is_string()) return at::fail("answer a name question with a string");
      answer.text = value.get<std::string>();
      break;
    case quiz::QuestionKind::Order:
      if (!value.is_array()) return at::fail("answer an order question with a list of structures");
      answer.order = value.get<std::vector<std::string>>();
      break;
  }
  return answer;
}

Result<bool> LessonPanel::scriptAction(const std::string& what, const json& a) {
  if (what == "lesson") return scriptStartLesson(a);
  if (pending_) return false;  // the other actions wait for a lesson being prepared
  if (auto st = scriptStep(what, a); !st) return tl::unexpected(st.error());
  return true;
}

// The same path as the Start button: the engine starts on its thread while frames go on.
Result<bool> LessonPanel::scriptStartLesson(const json& a) {
  if (!scriptStarting_) {
    const std::string lessonId = a.at("lesson").get<std::string>();
    auto s = store();
    if (!s) return tl::unexpected(s.error());
    if (a.contains("course")) {
      auto lesson = (*s)->curriculum.lesson(lessonId);
      if (!lesson) return tl::unexpected(lesson.error());
      if (lesson->courseId != a.at("course").get<std::string>())
        return at::fail("lesson '" + lessonId + "' belongs to course '" + lesson->courseId + "', not '" +
                        a.at("course").get<std::string>() + "'");
    }
    auto mode = lessons::parseLessonMode(a.value("mode", "guided"));
    if (!mode) return tl::unexpected(mode.error());
    if (auto st = startLesson(lessonId, *mode); !st) return tl::unexpected(st.error());
    scriptStarting_ = true;
  }
  pollStart();
  if (pending_) return false;
  scriptStarting_ = false;
  const Status result = startResult_.value_or(Status{});
  startResult_.reset();
  if (!result) return tl::unexpected(result.error());
  return true;
}

Status LessonPanel::scriptStep(const std::string& what, const json& a) {
  if (what == "lessons") {  // selects a course and reports its lesson list as shown
    auto s = store();
    if (!s) return tl::unexpected(s.error());
    if (a.contains("course")) {
      const std::string id = a.at("course").get<std::string>();
      auto it = std::find_if(courses_.begin(), courses_.end(), [&](const lessons::Course& c) { return c.id == id; });
      if (it == courses_.end()) return at::fail("unknown course '" + id + "'");
      courseIndex_ = int(it - courses_.begin());
    }
    if (auto st = refresh(); !st) return st;
    json list = json::array();
    for (const LessonRow& row : rows_) {
      json l = {{"id", row.id}, {"locked", !row.missing.empty()}, {"missing", row.missing},
                {"attempts", row.attempts}, {"open", row.open}};
      l["best_score"] = row.bestScore ? json(*row.bestScore) : json(nullptr);
      list.push_back(l);
    }
    events_({{"event", "lessons"}, {"course", courses_.empty() ? "" : courses_[std::size_t(courseIndex_)].id},
             {"lessons", list}});
    return {};
  }
  if (what == "lesson_next") return nextStep();
  if (what == "lesson_user") return switchUser(a.at("name").get<std::string>());
  if (what == "lesson_close") {
    step_.reset();
    asked_.reset();
    finishedScore_.reset();
    if (store_) store_->engine.reset();
    return {};
  }
  if (what == "review") {
    auto s = store();
    if (!s) return tl::unexpected(s.error());
    json due = json::array();
    for (const lessons::StructureProgress& p : due_) due.push_back(p.structureId);
    events_({{"event", "review_queue"}, {"due", due}});
    return startReview();
  }
  // "answer"
  auto answer = answerFromScript(a.at("value"));
  if (!answer) return tl::unexpected(answer.error());
  auto grade = submit(*answer);
  if (!grade) return tl::unexpected(grade.error());
  return {};
}

}  // namespace at::app
