// The UI script's actions on the course editor: each calls the CourseEditor command the Course
// editor window's widget calls, on what the view shows (DesktopModel::captureView).
#include "lessons/course_json.h"
#include "script/script_interpreter.h"

namespace at::app {

using json = nlohmann::json;

namespace {

tl::unexpected<Error> courseError(const json& action, const Error& e) {
  return tl::unexpected(withContext("ui script: action " + action.dump(), e));
}

}  // namespace

ScriptInterpreter::Feature ScriptInterpreter::courseActions() {
  using S = ScriptInterpreter;
  const ScriptArgument path{"path", "the package file"};
  return {"courses",
          "the Course editor window and the Dataset menu",
          {
              {"course_new", {{"id", "the course id"}, {"title?", "its title"}}, "A new course on the dataset on screen.",
               &S::courseNew},
              {"course_open", {{"course", "a stored course id"}}, "Opens a stored course to edit.", &S::courseOpen},
              {"course_lesson", {{"title?", "add a lesson so named"}, {"index?", "choose this lesson"}, {"prerequisites?", "[lesson ids] of the chosen lesson"}},
               "Adds or chooses a lesson, or sets its prerequisites.", &S::courseLesson},
              {"course_show", {{"title", "the step's title"}, {"text", "its text"}}, "Adds a show step of what the view shows.",
               &S::courseShow},
              {"course_question", {{"question", "a course-file question (its id optional)"}, {"scene?", "true: asked on what the view shows"}},
               "Adds a question step (a locate question needs scene).", &S::courseQuestion},
              {"course_step", {{"op", "move, duplicate, delete or preview"}, {"index", "the step"}, {"to?", "where to move it"}},
               "Edits a step of the chosen lesson.", &S::courseStep},
              {"course_save", {}, "Saves the course.", &S::courseSave},
              {"course_export", {path, {"reference_volume?", "true: leave the volume out, referenced by its checksum (default false: included)"},
                                 {"note?", "where to get a referenced volume"}},
               "Exports the course as a package.", &S::courseSave},
              {"course_open_package", {path, {"volume?", "the scan a package references (a file, a DICOM folder or a detached NRRD header)"}}, "Opens a course package.",
               &S::courseSave},
              {"open_dataset", {{"name", "a dataset"}}, "Switches the dataset, as the Dataset menu does.", &S::openDataset},
          }};
}

// {"do": "course_new", "id": "ear_tour", "title": "…"}: a course on the dataset on screen.
ScriptInterpreter::Outcome ScriptInterpreter::courseNew(Context& c) {
  CourseEditor& e = c.model.courseEditor();
  if (auto st = e.newCourse(c.action.at("id").get<std::string>(), c.action.value("title", ""), c.model.courseDatasetId()); !st)
    return courseError(c.action, st.error());
  return Progress::Done;
}

// {"do": "course_open", "course": ID}: a stored course, to edit.
ScriptInterpreter::Outcome ScriptInterpreter::courseOpen(Context& c) {
  if (auto st = c.model.courseEditor().openCourse(c.action.at("course").get<std::string>()); !st) return courseError(c.action, st.error());
  return Progress::Done;
}

// {"do": "course_lesson", "title": T} adds a lesson; {"index": N} chooses one; "prerequisites":
// [lesson ids] sets the chosen lesson's.
ScriptInterpreter::Outcome ScriptInterpreter::courseLesson(Context& c) {
  CourseEditor& e = c.model.courseEditor();
  Status st;
  if (c.action.contains("title")) st = e.addLesson(c.action.at("title").get<std::string>());
  if (st && c.action.contains("index")) st = e.selectLesson(c.action.at("index").get<std::size_t>());
  if (st && c.action.contains("prerequisites")) st = e.setPrerequisites(c.action.at("prerequisites").get<std::vector<std::string>>());
  if (!st) return courseError(c.action, st.error());
  return Progress::Done;
}

// {"do": "course_show", "title": T, "text": X}: a show step of what the view shows.
ScriptInterpreter::Outcome ScriptInterpreter::courseShow(Context& c) {
  auto capture = c.model.captureView();
  if (!capture) return courseError(c.action, capture.error());
  if (auto st = c.model.courseEditor().addShow(*capture, c.action.at("title").get<std::string>(), c.action.at("text").get<std::string>()); !st)
    return courseError(c.action, st.error());
  return Progress::Done;
}

// {"do": "course_question", "question": {course-file question, "id" optional}, "scene": true}: a
// question step; with "scene", asked on what the view shows (a locate question needs it). A locate
// question's view is checked on the editor's worker while frames go on: the script goes on once it
// is added, and fails with the reason when it is refused.
ScriptInterpreter::Outcome ScriptInterpreter::courseQuestion(Context& c) {
  CourseEditor& e = c.model.courseEditor();
  if (!c.first) {
    if (e.checking()) return Progress::Running;
    if (e.checkError()) return courseError(c.action, *e.checkError());
    return Progress::Done;
  }
  json q = c.action.at("question");
  const bool newId = !q.contains("id");
  if (newId) q["id"] = "new";
  auto question = lessons::parseQuestionJson(q.dump(), "ui script: course_question");
  if (!question) return tl::unexpected(question.error());
  if (newId) question->id.clear();
  std::optional<CourseEditor::Capture> scene;
  if (c.action.value("scene", false)) {
    auto capture = c.model.captureView();
    if (!capture) return courseError(c.action, capture.error());
    scene = *capture;
  }
  if (auto st = e.addQuestion(*question, scene); !st) return courseError(c.action, st.error());
  return e.checking() ? Progress::Running : Progress::Done;
}

// {"do": "course_step", "op": "move"|"duplicate"|"delete"|"preview", "index": N, "to": M}.
ScriptInterpreter::Outcome ScriptInterpreter::courseStep(Context& c) {
  CourseEditor& e = c.model.courseEditor();
  const std::string op = c.action.at("op").get<std::string>();
  const std::size_t index = c.action.at("index").get<std::size_t>();
  Status st;
  if (op == "move") st = e.moveStep(index, c.action.at("to").get<std::size_t>());
  else if (op == "duplicate") st = e.duplicateStep(index);
  else if (op == "delete") st = e.deleteStep(index);
  else if (op == "preview") st = e.previewStep(index);
  else return fail("ui script: course_step: \"op\" must be move, duplicate, delete or preview, got \"" + op + "\"");
  if (!st) return courseError(c.action, st.error());
  return Progress::Done;
}

// {"do": "course_save"}, {"do": "course_export", "path": F, "reference_volume": false, "note": ""},
// {"do": "course_open_package", "path": F, "volume": V}: as the window's buttons.
ScriptInterpreter::Outcome ScriptInterpreter::courseSave(Context& c) {
  CourseEditor& e = c.model.courseEditor();
  const std::string what = c.action.at("do").get<std::string>();
  Status st;
  if (what == "course_save") {
    if (auto saved = e.save(); !saved) st = tl::unexpected(saved.error());
  } else if (what == "course_export") {
    if (auto r = e.exportPackage(c.action.at("path").get<std::string>(), c.action.value("reference_volume", false),
                                 c.action.value("note", ""));
        !r)
      st = tl::unexpected(r.error());
  } else {
    if (auto r = e.openPackage(c.action.at("path").get<std::string>(), c.action.value("volume", "")); !r)
      st = tl::unexpected(r.error());
  }
  if (!st) return courseError(c.action, st.error());
  return Progress::Done;
}

// {"do": "open_dataset", "name": N}: the Dataset menu's entry.
ScriptInterpreter::Outcome ScriptInterpreter::openDataset(Context& c) {
  if (auto st = c.model.switchDataset(c.action.at("name").get<std::string>()); !st) return courseError(c.action, st.error());
  return Progress::Done;
}

}  // namespace at::app
