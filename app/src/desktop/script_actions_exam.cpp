// The UI script's exam actions. Each calls the ExamController (or model) command the exam panel's
// widget calls; every action but "exam" waits while an exam is being prepared.
#include "script_answers.h"
#include "script_interpreter.h"

namespace at::app {

using json = nlohmann::json;

ScriptInterpreter::Feature ScriptInterpreter::examActions() {
  using S = ScriptInterpreter;
  return {"exams",
          "the Exams panel: exams of the course, their items and results",
          {
              {"exams", {}, "Reports the course's exams as listed: exams [{id, locked, missing, items, time_limit_s, latest}].",
               &S::examList},
              {"exam", {{"exam", "an exam id"}}, "Starts the exam as the Start button does; done once its items are drawn.",
               &S::exam},
              {"exam_item", {{"position", "the item's position"}}, "Goes to that item.", &S::examItem},
              {"exam_answer", {{"value", "a choice's index, id or name; a typed name; a list (order)"}},
               "Answers the item on screen (a locate item: click, click_structure or slice_click).", &S::examAnswer},
              {"slice_click", {{"x", "pixel of the slice image"}, {"y", "pixel of the slice image"}},
               "Clicks the exam's slice image there (waits for the answer's distance field).", &S::sliceClick},
              {"slice_click_structure", {{"structure", "a structure id"}},
               "Clicks the structure's pixel nearest its in-slice centre; reports slice_click_structure {on_slice}.",
               &S::sliceClickStructure},
              {"exam_finish", {}, "Hands the exam in.", &S::examFinish},
              {"exam_leave", {}, "Leaves the exam.", &S::examLeave},
              {"exam_review_item", {{"index", "the row of the results"}, {"slice?", "true: its slice button (default false)"}},
               "Shows a row of the exam's results as its show (or slice) button does.", &S::examReviewItem},
          }};
}

// Reports the exams of the lesson panel's course as the panel lists them [exams].
ScriptInterpreter::Outcome ScriptInterpreter::examList(Context& c) {
  ExamController& x = c.model.exams();
  if (x.preparing()) return Progress::Running;
  if (auto st = x.refresh(); !st) return actionError(c.action, st.error());
  json list = json::array();
  for (const ExamController::ExamRow& row : x.rows()) {
    json e = {{"id", row.id}, {"locked", !row.missing.empty()}, {"missing", row.missing}, {"items", row.count},
              {"time_limit_s", row.timeLimitS}};
    if (row.latest) {
      e["latest"] = {{"finished", row.latest->finishedAt.has_value()}, {"score", row.latest->score}};
      e["latest"]["passed"] = row.latest->passed ? json(*row.latest->passed) : json(nullptr);
    }
    list.push_back(e);
  }
  c.model.event({{"event", "exams"}, {"exams", list}});
  return Progress::Done;
}

// The same path as the Start button: the items are drawn on a thread while frames go on.
ScriptInterpreter::Outcome ScriptInterpreter::exam(Context& c) {
  ExamController& x = c.model.exams();
  if (c.first)
    if (auto st = x.start(c.action.at("exam").get<std::string>()); !st) return actionError(c.action, st.error());
  x.poll();
  auto result = x.takeStartResult();
  if (!result) return Progress::Running;
  if (!*result) return actionError(c.action, result->error());
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::examItem(Context& c) {
  if (c.model.exams().preparing()) return Progress::Running;
  if (auto st = c.model.exams().goTo(c.action.at("position").get<int>()); !st) return actionError(c.action, st.error());
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::examAnswer(Context& c) {
  ExamController& x = c.model.exams();
  if (x.preparing()) return Progress::Running;
  const auto& item = x.item();
  if (!x.running() || !item) return actionError(c.action, Error{ErrorKind::Invalid, "no exam item is on screen"});
  auto answer = scriptAnswer(item->kind, item->choiceIds, item->choiceNames, c.action.at("value"));
  if (!answer) return actionError(c.action, answer.error());
  if (auto st = x.answer(*answer); !st) return actionError(c.action, st.error());
  return Progress::Done;
}

// A click at pixel {x, y} of the exam's slice image.
ScriptInterpreter::Outcome ScriptInterpreter::sliceClick(Context& c) {
  if (c.first) {
    if (!c.model.examSlice()) return actionError(c.action, Error{ErrorKind::Invalid, "no slice is on screen"});
    c.model.clickSlice(c.action.at("x").get<double>(), c.action.at("y").get<double>());
  }
  return c.model.fields().clickPending() ? Progress::Running : Progress::Done;
}

// A click on the structure's pixel nearest its in-slice centre [slice_click_structure].
ScriptInterpreter::Outcome ScriptInterpreter::sliceClickStructure(Context& c) {
  if (c.first) {
    if (!c.model.examSlice()) return actionError(c.action, Error{ErrorKind::Invalid, "no slice is on screen"});
    const std::string id = c.action.at("structure").get<std::string>();
    const Structure* s = c.model.dataset().findStructure(id);
    if (!s) return actionError(c.action, Error{ErrorKind::NotFound, "no structure '" + id + "' in the dataset"});
    const auto p = c.model.slicePixelOf(s->label);
    c.model.event({{"event", "slice_click_structure"}, {"structure", id}, {"on_slice", p.has_value()}});
    if (p) c.model.clickSlice((*p)[0], (*p)[1]);
  }
  return c.model.fields().clickPending() ? Progress::Running : Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::examFinish(Context& c) {
  if (c.model.exams().preparing()) return Progress::Running;
  if (auto st = c.model.exams().finish(); !st) return actionError(c.action, st.error());
  return Progress::Done;
}

// {"do": "exam_review_item", "index": i, "slice": false}: a row of the exam's results, shown as
// its "show" (or "slice") button shows it.
ScriptInterpreter::Outcome ScriptInterpreter::examReviewItem(Context& c) {
  if (c.model.exams().preparing()) return Progress::Running;
  if (auto st = c.model.exams().showResultItem(c.action.value("index", -1), c.action.value("slice", false)); !st)
    return actionError(c.action, st.error());
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::examLeave(Context& c) {
  if (c.model.exams().preparing()) return Progress::Running;
  c.model.exams().leave();
  return Progress::Done;
}

}  // namespace at::app
