// The UI script's lesson actions: each calls the LessonController command the Lessons panel's
// widget calls; every action but "lesson" waits while a lesson is being prepared.
#include "script_answers.h"
#include "script_interpreter.h"

namespace at::app {

using json = nlohmann::json;

ScriptInterpreter::Feature ScriptInterpreter::lessonActions() {
  using S = ScriptInterpreter;
  const ScriptArgument slice{"slice?", "true: the \"on a slice\" button instead (default false)"};
  return {"lessons",
          "the Lessons panel: courses, lessons, answers and the review of due structures",
          {
              {"lesson_user", {{"name", "the user (created when new)"}}, "Switches whose progress the panel shows and records.",
               &S::lessonUser},
              {"lessons", {{"course?", "a course id (default: the one selected)"}},
               "Selects the course and reports its lessons as listed: lessons [{id, locked, missing, attempts, open, best_score}].",
               &S::lessonList},
              {"lesson",
               {{"lesson", "a lesson id"}, {"course?", "the course it must belong to"}, {"mode?", "guided (default) or quiz_only"}},
               "Starts the lesson as the Start button does; done once its first step is shown.", &S::lesson},
              {"lesson_next", {}, "The Next button: the lesson's next step.", &S::lessonNext},
              {"lesson_back", {}, "The Back button: the step before.", &S::lessonReview},
              {"show_me", {slice}, "The Show me button: the asked structure shown in the view (or on a slice).", &S::lessonReview},
              {"lesson_review_item", {{"index", "the row of the lesson's answers"}, slice},
               "A row of the finished lesson's answers, shown as its button shows it.", &S::lessonReview},
              {"answer", {{"value", "a choice's index, id or name; a typed name; a list (order); or a play --answers object"}},
               "Answers the question asked (a locate question is answered by click, click_structure or slice_click).",
               &S::answer},
              {"review", {}, "Reports review_queue {due, names} and starts the review of the due structures.", &S::review},
              {"lesson_close", {}, "Leaves the lesson.", &S::lessonClose},
          }};
}

ScriptInterpreter::Outcome ScriptInterpreter::lessonUser(Context& c) {
  if (c.model.lessons().preparing()) return Progress::Running;
  if (auto st = c.model.lessons().switchUser(c.action.at("name").get<std::string>()); !st) return actionError(c.action, st.error());
  return Progress::Done;
}

// Selects a course and reports its lesson list as shown [lessons].
ScriptInterpreter::Outcome ScriptInterpreter::lessonList(Context& c) {
  LessonController& l = c.model.lessons();
  if (l.preparing()) return Progress::Running;
  if (auto st = l.ready(); !st) return actionError(c.action, st.error());
  if (c.action.contains("course")) {
    if (auto st = l.selectCourse(c.action.at("course").get<std::string>()); !st) return actionError(c.action, st.error());
  } else if (auto st = l.refresh(); !st) {
    return actionError(c.action, st.error());
  }
  json list = json::array();
  for (const LessonController::LessonRow& row : l.rows()) {
    json e = {{"id", row.id}, {"locked", !row.missing.empty()}, {"missing", row.missing},
              {"attempts", row.attempts}, {"open", row.open}};
    e["best_score"] = row.bestScore ? json(*row.bestScore) : json(nullptr);
    list.push_back(e);
  }
  c.model.event({{"event", "lessons"}, {"course", l.courses().empty() ? "" : l.courses()[std::size_t(l.courseIndex())].id},
                 {"lessons", list}});
  return Progress::Done;
}

// The same path as the Start button: the engine starts on its thread while frames go on.
ScriptInterpreter::Outcome ScriptInterpreter::lesson(Context& c) {
  LessonController& l = c.model.lessons();
  if (c.first) {
    const std::string lessonId = c.action.at("lesson").get<std::string>();
    if (c.model.exams().running() || c.model.exams().preparing())
      return actionError(c.action, Error{ErrorKind::Conflict, "an exam is running: finish or leave it first"});
    if (auto st = l.ready(); !st) return actionError(c.action, st.error());
    if (c.action.contains("course")) {
      const std::string course = c.action.at("course").get<std::string>();
      for (const lessons::Course& k : l.courses())
        for (const lessons::Lesson& lesson : k.lessons)
          if (lesson.id == lessonId && k.id != course)
            return fail("ui script: lesson '" + lessonId + "' belongs to course '" + k.id + "', not '" + course + "'");
    }
    auto mode = lessons::parseLessonMode(c.action.value("mode", "guided"));
    if (!mode) return actionError(c.action, mode.error());
    if (auto st = l.startLesson(lessonId, *mode); !st) return actionError(c.action, st.error());
  }
  l.poll();
  auto result = l.takeStartResult();
  if (!result) return Progress::Running;
  if (!*result) return actionError(c.action, result->error());
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::lessonNext(Context& c) {
  if (c.model.lessons().preparing()) return Progress::Running;
  if (auto st = c.model.lessons().next(); !st) return actionError(c.action, st.error());
  return Progress::Done;
}

// {"do": "lesson_back"}, {"do": "show_me"}, {"do": "lesson_review_item", "index": i}: the
// Lessons panel's Back, Show me and review rows; with "slice": true their "on a slice" buttons.
ScriptInterpreter::Outcome ScriptInterpreter::lessonReview(Context& c) {
  LessonController& l = c.model.lessons();
  if (l.preparing()) return Progress::Running;
  const std::string verb = c.action.at("do").get<std::string>();
  const bool onSlice = c.action.value("slice", false);
  Status st = verb == "lesson_back" ? l.back()
              : verb == "show_me"   ? l.showMe(onSlice)
                                    : l.showReviewItem(c.action.value("index", -1), onSlice);
  if (!st) return actionError(c.action, st.error());
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::answer(Context& c) {
  LessonController& l = c.model.lessons();
  if (l.preparing()) return Progress::Running;
  const LessonController::Asked* asked = l.asked();
  if (!asked) return actionError(c.action, Error{ErrorKind::Invalid, "no question is asked"});
  auto answer = scriptAnswer(asked->question.question.kind, asked->question.choices, asked->choiceNames, c.action.at("value"));
  if (!answer) return actionError(c.action, answer.error());
  if (auto grade = l.answer(*answer); !grade) return actionError(c.action, grade.error());
  return Progress::Done;
}

// [review_queue, review_question]; "answer" then answers it.
ScriptInterpreter::Outcome ScriptInterpreter::review(Context& c) {
  LessonController& l = c.model.lessons();
  if (l.preparing()) return Progress::Running;
  if (auto st = l.ready(); !st) return actionError(c.action, st.error());
  json due = json::array(), names = json::array();  // ids, and the names the panel's due list shows
  for (const lessons::StructureProgress& p : l.due()) {
    due.push_back(p.structureId);
    names.push_back(l.displayName(p.structureId));
  }
  c.model.event({{"event", "review_queue"}, {"due", due}, {"names", names}});
  if (auto st = l.startReview(); !st) return actionError(c.action, st.error());
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::lessonClose(Context& c) {
  if (c.model.lessons().preparing()) return Progress::Running;
  c.model.lessons().leave();
  return Progress::Done;
}

}  // namespace at::app
