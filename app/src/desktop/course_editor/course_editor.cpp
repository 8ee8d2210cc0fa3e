#include "course_editor/course_editor.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <exception>
#include <set>
#include <thread>

#include "core/strings.h"
#include "course_authoring.h"
#include "lesson_player/lesson_controller.h"
#include "db/preset_store.h"
#include "lessons/course_check.h"
#include "lessons/course_json.h"

namespace at::app {

using json = nlohmann::json;

namespace {

bool plainId(const std::string& id) {
  return !id.empty() && std::all_of(id.begin(), id.end(), [](unsigned char c) { return std::islower(c) || std::isdigit(c) || c == '_'; });
}

// Every question id of `course`.
std::set<std::string> questionIds(const lessons::Course& course) {
  std::set<std::string> ids;
  for (const lessons::Lesson& l : course.lessons)
    for (const lessons::Step& s : l.steps)
      if (s.kind == lessons::StepKind::Question) ids.insert(s.question.id);
  return ids;
}

// `base`, else `base` + "_2", "_3", … : the first not in `taken`.
std::string freeId(const std::string& base, const std::set<std::string>& taken) {
  if (!taken.count(base)) return base;
  for (int n = 2;; ++n)
    if (!taken.count(base + "_" + std::to_string(n))) return base + "_" + std::to_string(n);
}

// The course as it is stored: lessons still without a step (the default "Lesson 1" an author
// did not use) are left out when another lesson has steps, so they do not block saving.
lessons::Course storedForm(const lessons::Course& draft) {
  const bool anySteps = std::any_of(draft.lessons.begin(), draft.lessons.end(), [](const lessons::Lesson& l) { return !l.steps.empty(); });
  if (!anySteps) return draft;
  lessons::Course course = draft;
  course.lessons.erase(std::remove_if(course.lessons.begin(), course.lessons.end(), [](const lessons::Lesson& l) { return l.steps.empty(); }),
                       course.lessons.end());
  return course;
}

}  // namespace

// A locate question being checked: the snapshot taken when it was asked, and the check's work on
// its own thread.
struct CourseEditor::CheckJob {
  std::atomic<bool> cancel{false};
  std::atomic<bool> finished{false};
  std::optional<Result<LocateCheck>> result;  // written by the worker before `finished`
  std::string lessonId;                       // the lesson chosen when the question was asked
  lessons::Step step;                         // the question and its scene, as asked
  Capture scene;
  bool freshId = false;                       // the editor made the id (made again if taken meanwhile)
  std::optional<std::string> dropped;         // why the result is no longer wanted (UI thread only)
  std::chrono::steady_clock::time_point start;
  std::jthread thread;  // last: joined before the members above go
};

CourseEditor::CourseEditor(LearningSession& session, const render::PresetLibrary& library, EventSink events, Preview preview,
                           LocateViewCheck checkLocate)
    : session_(session),
      library_(library),
      events_(std::move(events)),
      preview_(std::move(preview)),
      checkLocate_(std::move(checkLocate)) {}

CourseEditor::~CourseEditor() {
  if (job_) job_->cancel = true;
  job_.reset();  // joins the worker (no event: the sinks may be going too)
}

Result<lessons::Lesson*> CourseEditor::lesson() {
  if (!draft_) return fail("no course is being edited: make a new one or open one");
  if (lesson_ >= draft_->lessons.size()) return fail("the course has no lesson: add one");
  return &draft_->lessons[lesson_];
}

void CourseEditor::changed() {
  ++revision_;
  previewing_.reset();
  problems_.clear();
  // The form, as the course reader sees it (the first problem, by field path) …
  auto parsed = lessons::parseCourseJson(lessons::courseToJson(storedForm(*draft_)), draft_->id);
  if (!parsed) problems_.push_back(parsed.error().message.substr(std::min(parsed.error().message.size(), draft_->id.size() + 2)));
  // … and every structure it names against the dataset.
  auto structures = session_.structures(draft_->datasetId);
  if (!structures) {
    problems_.push_back("dataset: " + structures.error().message);
  } else {
    std::set<std::string> ids;
    for (const Structure& s : *structures) ids.insert(s.id);
    for (std::string& p : lessons::unknownStructureReferences(*draft_, ids)) problems_.push_back(std::move(p));
  }
  events_(stateEvent());
}

json CourseEditor::stateEvent() const {
  json steps = json::array();
  if (draft_ && lesson_ < draft_->lessons.size())
    for (const lessons::Step& s : draft_->lessons[lesson_].steps) {
      if (s.kind == lessons::StepKind::Show)
        steps.push_back({{"kind", "show"}, {"structure", s.show.structure}, {"preset", s.show.presetId}, {"title", s.show.title}});
      else if (s.kind == lessons::StepKind::Question)
        steps.push_back({{"kind", quiz::toString(s.question.kind)}, {"id", s.question.id}, {"target", s.question.target}});
      else
        steps.push_back({{"kind", "study"}, {"structure", s.study.structure}});
    }
  json lessons = json::array();
  if (draft_)
    for (const lessons::Lesson& l : draft_->lessons) lessons.push_back(l.id);
  return {{"event", "course_edited"},      {"course", draft_ ? draft_->id : ""}, {"version", draft_ ? draft_->version : 0},
          {"lessons", lessons},             {"lesson", lesson_},                  {"steps", steps},
          {"problems", problems_}};
}

Status CourseEditor::newCourse(const std::string& id, const std::string& title, const std::string& datasetId) {
  if (!plainId(id)) return fail("course id '" + id + "': use lower-case letters, digits and '_'");
  if (auto stored = session_.curriculum().course(id))
    return fail(ErrorKind::Conflict, "course '" + id + "' already exists: open it to edit it");
  lessons::Course course;
  course.id = id;
  course.title = title.empty() ? id : title;
  course.datasetId = datasetId;
  lessons::Lesson first;
  first.id = id + ".lesson_1";
  first.courseId = id;
  first.title = "Lesson 1";
  course.lessons.push_back(first);
  dropCheck("a new course was started while its view was being checked");
  draft_ = std::move(course);
  storedVersion_.reset();
  captured_.clear();
  lesson_ = 0;
  windowOpen = true;
  changed();
  return {};
}

Status CourseEditor::openCourse(const std::string& courseId) {
  auto course = session_.curriculum().course(courseId);
  if (!course) return tl::unexpected(course.error());
  dropCheck("another course was opened while its view was being checked");
  storedVersion_ = course->version;
  draft_ = std::move(*course);
  captured_.clear();
  lesson_ = 0;
  windowOpen = true;
  changed();
  return {};
}

Status CourseEditor::setTitle(const std::string& title, const std::string& summary) {
  if (!draft_) return fail("no course is being edited");
  draft_->title = title;
  draft_->summary = summary;
  changed();
  return {};
}

Status CourseEditor::addLesson(const std::string& title) {
  if (!draft_) return fail("no course is being edited: make a new one or open one");
  const std::string slug = str::identifier(title);
  if (slug.empty()) return fail("a lesson needs a title with a letter or digit");
  std::set<std::string> taken;
  for (const lessons::Lesson& l : draft_->lessons) taken.insert(l.id);
  lessons::Lesson lesson;
  lesson.id = freeId(draft_->id + "." + slug, taken);
  lesson.courseId = draft_->id;
  lesson.title = title;
  draft_->lessons.push_back(lesson);
  lesson_ = draft_->lessons.size() - 1;
  changed();
  return {};
}

Status CourseEditor::selectLesson(std::size_t index) {
  if (!draft_ || index >= draft_->lessons.size()) return fail("no lesson " + std::to_string(index));
  lesson_ = index;
  previewing_.reset();
  events_(stateEvent());
  return {};
}

Status CourseEditor::setPrerequisites(const std::vector<std::string>& lessonIds) {
  auto found = lesson();
  if (!found) return tl::unexpected(found.error());
  lessons::Lesson* l = *found;
  l->prerequisites = lessonIds;
  changed();
  return {};
}

std::string CourseEditor::capturePreset(const lessons::Lesson& l, const Capture& capture) {
  std::set<std::string> taken;
  for (const auto& [id, preset] : captured_) taken.insert(id);
  const std::string id = freeId(l.id + ".show_" + std::to_string(l.steps.size() + 1), taken);
  render::Preset preset = capture.preset;
  preset.id = id;
  preset.structure = capture.structure;
  preset.view = lessons::toString(capture.view);
  captured_[id] = preset;
  return id;
}

Status CourseEditor::addShow(const Capture& capture, const std::string& title, const std::string& text) {
  if (auto free = requireNoCheck(); !free) return free;
  auto found = lesson();
  if (!found) return tl::unexpected(found.error());
  lessons::Lesson* l = *found;
  if (capture.structure.empty()) return fail("select a structure to show first");
  lessons::Step step;
  step.kind = lessons::StepKind::Show;
  step.show.structure = capture.structure;
  step.show.presetId = capturePreset(*l, capture);
  step.show.view = capture.view;
  step.show.camera = capture.camera;
  step.show.clip = capture.clip;
  step.show.title = title;
  step.show.text = text;
  l->steps.push_back(step);
  changed();
  return {};
}

Status CourseEditor::addQuestion(quiz::Question question, const std::optional<Capture>& scene) {
  checkError_.reset();
  if (auto free = requireNoCheck(); !free) return free;
  auto found = lesson();
  if (!found) return tl::unexpected(found.error());
  lessons::Lesson* l = *found;
  const std::set<std::string> taken = questionIds(*draft_);
  const bool freshId = question.id.empty();
  question.id = freshId ? freeId(l->id + ".q" + std::to_string(l->steps.size() + 1), taken) : question.id;
  if (taken.count(question.id)) return fail(ErrorKind::Conflict, "question id '" + question.id + "' is already in the course");
  lessons::Step step;
  step.kind = lessons::StepKind::Question;
  step.question = std::move(question);
  if (scene) {
    lessons::QuestionScene s;
    s.structure = scene->structure;
    s.view = scene->view;
    s.camera = scene->camera;
    s.clip = scene->clip;
    step.scene = s;  // its preset id once added (appendQuestion)
  }
  if (!scene || step.question.kind != quiz::QuestionKind::Locate || !checkLocate_)
    return appendQuestion(l->id, std::move(step), scene, freshId);
  // The check on the worker, on this snapshot; poll() applies its result.
  auto job = std::make_unique<CheckJob>();
  job->lessonId = l->id;
  job->step = std::move(step);
  job->scene = *scene;
  job->freshId = freshId;
  job->start = std::chrono::steady_clock::now();
  LocateCheckWork work = checkLocate_(job->step.question, *job->step.scene, job->scene.preset);
  CheckJob* j = job.get();
  job->thread = std::jthread([j, work = std::move(work)] {
    try {
      j->result = work(j->cancel);
    } catch (const std::exception& e) {  // not to end the program from a worker thread
      j->result = fail(std::string("the view could not be checked: ") + e.what());
    }
    j->finished.store(true, std::memory_order_release);
  });
  job_ = std::move(job);
  events_({{"event", "course_question_checking"}, {"question", job_->step.question.id}, {"target", job_->step.question.target}});
  return {};
}

Status CourseEditor::appendQuestion(const std::string& lessonId, lessons::Step step, const std::optional<Capture>& scene,
                                    bool freshId) {
  if (!draft_) return fail("no course is being edited: make a new one or open one");
  const auto l = std::find_if(draft_->lessons.begin(), draft_->lessons.end(), [&](const lessons::Lesson& x) { return x.id == lessonId; });
  if (l == draft_->lessons.end()) return fail(ErrorKind::NotFound, "question not added: the course has no lesson '" + lessonId + "'");
  const std::set<std::string> taken = questionIds(*draft_);
  if (taken.count(step.question.id)) {
    if (!freshId) return fail(ErrorKind::Conflict, "question id '" + step.question.id + "' is already in the course");
    step.question.id = freeId(l->id + ".q" + std::to_string(l->steps.size() + 1), taken);
  }
  if (scene) step.scene->presetId = capturePreset(*l, *scene);
  l->steps.push_back(std::move(step));
  changed();
  return {};
}

Status CourseEditor::requireNoCheck() const {
  if (!job_) return {};
  return fail(ErrorKind::Conflict, "the locate question '" + job_->step.question.id +
                                       "' is still being checked: add the next step once it is added or refused");
}

void CourseEditor::poll() {
  if (!job_ || !job_->finished.load(std::memory_order_acquire)) return;
  std::unique_ptr<CheckJob> job = std::move(job_);
  job->thread.join();
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - job->start).count();
  const std::string id = job->step.question.id;
  Status st;
  if (job->dropped) st = fail(ErrorKind::Cancelled, "question not added: " + *job->dropped);
  else if (!*job->result) st = tl::unexpected(withContext("question not added", job->result->error()));
  else if (!(*job->result)->answerable) st = fail("question not added: " + (*job->result)->problem);
  else st = appendQuestion(job->lessonId, std::move(job->step), job->scene, job->freshId);
  json e = {{"event", "course_question_checked"}, {"question", id}, {"added", bool(st)}, {"ms", ms}};
  if (!st) {
    checkError_ = st.error();
    e["message"] = st.error().message;
  }
  events_(std::move(e));
}

void CourseEditor::dropCheck(const std::string& why) {
  if (!job_) return;
  job_->cancel = true;  // poll() takes it once its work returns
  job_->dropped = why;
}

void CourseEditor::stopCheck() {
  if (!job_) return;
  job_->cancel = true;
  const std::string id = job_->step.question.id;
  job_.reset();  // joins the worker
  checkError_ = Error{ErrorKind::Cancelled, "question not added: its view check was stopped before it ended"};
  events_({{"event", "course_question_checked"}, {"question", id}, {"added", false}, {"message", checkError_->message}});
}

Status CourseEditor::moveStep(std::size_t from, std::size_t to) {
  auto found = lesson();
  if (!found) return tl::unexpected(found.error());
  lessons::Lesson* l = *found;
  if (from >= l->steps.size() || to >= l->steps.size()) return fail("no step " + std::to_string(std::max(from, to)));
  lessons::Step step = std::move(l->steps[from]);
  l->steps.erase(l->steps.begin() + long(from));
  l->steps.insert(l->steps.begin() + long(to), std::move(step));
  changed();
  return {};
}

Status CourseEditor::duplicateStep(std::size_t index) {
  auto found = lesson();
  if (!found) return tl::unexpected(found.error());
  lessons::Lesson* l = *found;
  if (index >= l->steps.size()) return fail("no step " + std::to_string(index));
  lessons::Step copy = l->steps[index];
  if (copy.kind == lessons::StepKind::Question) copy.question.id = freeId(copy.question.id + "_copy", questionIds(*draft_));
  l->steps.insert(l->steps.begin() + long(index) + 1, std::move(copy));
  changed();
  return {};
}

Status CourseEditor::deleteStep(std::size_t index) {
  auto found = lesson();
  if (!found) return tl::unexpected(found.error());
  lessons::Lesson* l = *found;
  if (index >= l->steps.size()) return fail("no step " + std::to_string(index));
  l->steps.erase(l->steps.begin() + long(index));
  changed();
  return {};
}

Status CourseEditor::previewStep(std::size_t index) {
  auto found = lesson();
  if (!found) return tl::unexpected(found.error());
  lessons::Lesson* l = *found;
  if (index >= l->steps.size()) return fail("no step " + std::to_string(index));
  const lessons::Step& step = l->steps[index];
  if (step.kind == lessons::StepKind::Study) return fail("a study step has no view");
  const lessons::QuestionScene scene = step.kind == lessons::StepKind::Show
                                           ? lessons::QuestionScene{step.show.structure, step.show.presetId, step.show.view,
                                                                     step.show.camera, step.show.clip}
                                           : lessons::sceneFor(step);
  auto it = captured_.find(scene.presetId);
  preview_(scene, it != captured_.end() ? std::optional<render::Preset>(it->second) : std::nullopt);
  Previewing p;
  p.step = index;
  p.kind = step.kind;
  p.structure = scene.structure;
  if (step.kind == lessons::StepKind::Show) {
    p.heading = step.show.title;
    p.text = step.show.text;
  } else {
    p.heading = std::string("Question (") + quiz::toString(step.question.kind) + ")";
    p.text = step.question.prompt;
    p.namesHidden = namesGiveAway(step.question.kind);
  }
  previewing_ = p;
  events_({{"event", "course_preview"}, {"step", index}, {"kind", p.kind == lessons::StepKind::Show ? "show" : quiz::toString(step.question.kind)},
           {"structure", p.structure}, {"names_hidden", p.namesHidden}});
  return {};
}

Result<db::SeedOutcome> CourseEditor::save() {
  if (!draft_) return fail("no course is being edited");
  if (!problems_.empty()) return fail("course '" + draft_->id + "' cannot be saved: " + problems_.front());
  if (auto stored = session_.curriculum().course(draft_->id)) {
    if (lessons::courseToJson(*stored) != lessons::courseToJson(storedForm(*draft_)))
      draft_->version = std::max(draft_->version, stored->version + 1);
  }
  for (const auto& [id, preset] : captured_) {
    db::StoredPreset stored{id, preset.structure, render::toString(preset.mode), render::presetToJson(preset)};
    if (auto ok = db::savePreset(session_.database(), stored); !ok) return tl::unexpected(ok.error());
  }
  auto outcome = saveCourse(session_, storedForm(*draft_), "desktop course editor");
  if (!outcome) return tl::unexpected(outcome.error());
  storedVersion_ = draft_->version;
  events_({{"event", "course_saved"}, {"course", draft_->id}, {"version", draft_->version}, {"outcome", db::toString(*outcome)}});
  return *outcome;
}

Result<CourseExportReport> CourseEditor::exportPackage(const std::string& path, bool referenceVolume, const std::string& note) {
  if (auto saved = save(); !saved) return tl::unexpected(saved.error());
  CourseExportRequest request;
  request.courseId = draft_->id;
  request.out = path;
  request.referenceVolume = referenceVolume;
  request.referenceNote = note;
  auto report = exportCourse(session_, library_, request);
  if (!report) return tl::unexpected(report.error());
  events_({{"event", "course_exported"}, {"course", draft_->id}, {"path", path}, {"bytes", report->bytes},
           {"volume", package::toString(report->source)}});
  return report;
}

Result<CourseImportReport> CourseEditor::openPackage(const std::string& path, const std::string& volumePath) {
  CourseImportRequest request;
  request.package = path;
  request.volumePath = volumePath;
  auto report = importCoursePackage(session_, request);
  if (!report) return tl::unexpected(report.error());
  events_({{"event", "course_imported"}, {"course", report->courseId}, {"version", report->version},
           {"outcome", db::toString(report->outcome)}, {"dataset", report->datasetId}, {"dataset_action", toString(report->dataset)}});
  return report;
}

}  // namespace at::app
