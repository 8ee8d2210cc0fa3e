// The UI script's actions on the panels: lessons, the expert's preset, studies and imports. Each
// calls the controller command the panel's widget calls.
#include <cstdio>

#include "quiz/answer_json.h"
#include "script_answers.h"
#include "script_interpreter.h"

namespace at::app {

using json = nlohmann::json;

// A script's answer to the question asked: a choice (index, or a choice's id or name), a typed
// name, a list of structures (order), or a `play --answers` object.
Result<quiz::Answer> scriptAnswer(quiz::QuestionKind kind, const std::vector<std::string>& choiceIds,
                                  const std::vector<std::string>& choiceNames, const json& value) {
  if (value.is_object()) return quiz::answerFromJson(value.dump());
  quiz::Answer answer;
  switch (kind) {
    case quiz::QuestionKind::Locate:
      return fail("a locate question is answered by a click in the view (click, click_structure, slice_click)");
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation:
      if (value.is_number_integer()) {
        answer.choice = value.get<int>();
      } else if (value.is_string()) {  // the choice labelled so (its id or display name)
        const std::string wanted = value.get<std::string>();
        for (std::size_t i = 0; i < choiceIds.size(); ++i)
          if (choiceIds[i] == wanted || (i < choiceNames.size() && choiceNames[i] == wanted)) answer.choice = int(i);
        if (!answer.choice) return fail("'" + wanted + "' is not one of the choices");
      } else {
        return fail("answer a choice question with a number or a choice's id or name");
      }
      break;
    case quiz::QuestionKind::Name:
      if (!value.is_string()) return fail("answer a name question with a string");
      answer.text = value.get<std::string>();
      break;
    case quiz::QuestionKind::Order:
      if (!value.is_array()) return fail("answer an order question with a list of structures");
      answer.order = value.get<std::vector<std::string>>();
      break;
  }
  return answer;
}

tl::unexpected<Error> actionError(const json& action, const Error& e) {
  return tl::unexpected(withContext("ui script: action " + action.dump(), e));
}

// ---------------------------------------------------------------------------------------------
// Lessons: every action but "lesson" waits while a lesson is being prepared.

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

// ---------------------------------------------------------------------------------------------
// The expert's preset: opens the expert panel when it is closed.

ScriptInterpreter::Outcome ScriptInterpreter::tfEdit(Context& c) {
  if (!c.model.expertOn()) c.model.setExpert(true);
  TfEditor& e = c.model.expert();
  const std::string what = c.action.at("do");
  const std::string tf = c.action.value("tf", "");
  if (tf != "data" && tf != "distance") return actionError(c.action, Error{ErrorKind::Invalid, "\"tf\" must be \"data\" or \"distance\", got \"" + tf + "\""});
  const bool data = tf == "data";
  const auto rgba = [&]() -> std::optional<render::Rgba> {
    if (!c.action.contains("rgba")) return std::nullopt;
    const auto v = c.action.at("rgba").get<std::vector<float>>();
    if (v.size() != 4) throw std::invalid_argument("\"rgba\" must be 4 numbers");
    return render::Rgba{v[0], v[1], v[2], v[3]};
  };
  Status st;
  if (what == "tf_add_point") {
    auto i = e.addPoint(data, c.action.at("x").get<double>(), rgba());
    if (!i) st = tl::unexpected(i.error());
  } else {
    const std::size_t index = c.action.at("index").get<std::size_t>();
    const auto& pts = data ? e.preset().dataTf : e.preset().distanceTf;
    if (what != "tf_delete_point" && index >= pts.size()) return actionError(c.action, Error{ErrorKind::Invalid, "no point " + std::to_string(index)});
    if (what == "tf_move_point")
      st = e.movePoint(data, index, c.action.value("x", pts[index].x), c.action.value("alpha", pts[index].rgba[3]));
    else if (what == "tf_delete_point")
      st = e.deletePoint(data, index);
    else
      st = e.setColour(data, index, rgba().value_or(pts[index].rgba));
  }
  if (!st) return actionError(c.action, st.error());
  c.model.expertEdited();
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::presetSet(Context& c) {
  if (!c.model.expertOn()) c.model.setExpert(true);
  render::Preset p = c.model.expert().preset();
  const json& a = c.action;
  if (a.contains("mode")) {
    auto m = render::parseRenderMode(a.at("mode").get<std::string>());
    if (!m) return actionError(a, m.error());
    p.mode = *m;
  }
  p.t = a.value("t", p.t);
  p.alpha = a.value("alpha", p.alpha);
  p.lightingAlpha = a.value("lighting_alpha", p.lightingAlpha);
  p.lightingBeta = a.value("lighting_beta", p.lightingBeta);
  p.weightRule = a.value("rule", p.weightRule);
  p.weightBase = a.value("base", p.weightBase);
  if (a.contains("hu_window")) p.huWindow = a.at("hu_window").get<std::array<float, 2>>();
  if (auto st = c.model.expert().setParameters(p); !st) return actionError(a, st.error());
  c.model.expertEdited();
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::presetSave(Context& c) {
  if (!c.model.expertOn()) c.model.setExpert(true);
  const json& a = c.action;
  auto st = c.model.expert().saveAs(a.at("name").get<std::string>(), a.contains("export")
                                                                          ? std::optional<std::string>(a.at("export").get<std::string>())
                                                                          : std::nullopt);
  if (!st) return actionError(a, st.error());
  return Progress::Done;
}

// ---------------------------------------------------------------------------------------------
// Studies

// study_start and study_next are done once the participant screen they opened is on display, so
// every screen is shown (and announced as "study_screen") before the script acts on the next one.
ScriptInterpreter::Outcome ScriptInterpreter::awaitStudyScreen(Context& c) {
  if (!c.host.drawsPanels() || !c.model.study().screenPending()) return Progress::Done;
  if (c.elapsedMs > c.action.value("timeout_ms", 60000.0))
    return fail(ErrorKind::Unavailable, "ui script: " + c.action.at("do").get<std::string>() + ": the participant screen was never drawn");
  return Progress::Running;
}

ScriptInterpreter::Outcome ScriptInterpreter::studyStart(Context& c) {
  if (c.first) {
    auto st = c.model.study().startParticipant(c.action.at("study").get<std::string>(), c.action.at("participant").get<std::string>(),
                                               c.action.at("group").get<std::string>());
    if (!st) return tl::unexpected(st.error());
  }
  return awaitStudyScreen(c);
}

// study_toggle {side?}, study_rate {item, rating}, study_comment {text}, study_next, study_close
ScriptInterpreter::Outcome ScriptInterpreter::study(Context& c) {
  StudyController& s = c.model.study();
  const std::string what = c.action.at("do");
  if (!c.first && what == "study_rate") return studyRate(c);  // waiting for full quality
  if (!c.first) return awaitStudyScreen(c);  // study_next, waiting for its screen
  if (!s.participantActive()) return fail("ui script: " + what + " needs study_start first");
  Status st;
  if (what == "study_toggle") {
    const std::string side = c.action.value("side", "");
    s.showSide(side.empty() ? '?' : side[0]);
  } else if (what == "study_rate") {
    if (!s.participant()->trial) return fail("ui script: study_rate after the last trial");
    return studyRate(c);
  } else if (what == "study_comment") {
    s.setComment(c.action.at("text").get<std::string>());
  } else if (what == "study_next") {
    st = s.nextTrial();
  } else {
    s.closeParticipant();
  }
  if (!st) return tl::unexpected(withContext("ui script", st.error()));
  return what == "study_next" ? awaitStudyScreen(c) : Progress::Done;
}

// study_rate waits (as a participant must) until the side on screen has been drawn at full quality.
ScriptInterpreter::Outcome ScriptInterpreter::studyRate(Context& c) {
  StudyController& s = c.model.study();
  if (!s.readyToRate()) {
    if (c.elapsedMs > c.action.value("timeout_ms", 60000.0))
      return fail(ErrorKind::Unavailable, "ui script: study_rate: the view never reached full quality");
    return Progress::Running;
  }
  if (auto st = s.rate(c.action.at("item").get<std::string>(), c.action.at("rating").get<int>()); !st)
    return tl::unexpected(withContext("ui script", st.error()));
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::coordinatorOpen(Context& c) {
  StudyController& s = c.model.study();
  s.coordinatorOpen = true;
  s.refreshStudies();
  if (c.action.contains("study"))
    if (auto st = s.selectStudy(c.action.at("study").get<std::string>()); !st) return tl::unexpected(st.error());
  return Progress::Done;
}

// Started on the first call; done once the last file is written (one file per frame).
// "cancel_after": k presses Cancel once k files are written (deterministic).
ScriptInterpreter::Outcome ScriptInterpreter::coordinatorExport(Context& c) {
  StudyController& s = c.model.study();
  if (c.first) {
    if (c.action.contains("study")) {
      if (auto st = s.selectStudy(c.action.at("study").get<std::string>()); !st) return tl::unexpected(st.error());
    } else if (!s.selectedStudy()) {
      s.refreshStudies();
    }
    if (auto st = s.startExport(c.action.at("out").get<std::string>()); !st) return tl::unexpected(st.error());
    return Progress::Running;
  }
  const StudyExport* running = s.runningExport();
  if (!running) {
    if (s.exportFailed()) return fail(s.exportStatus());
    return Progress::Done;  // cancelled
  }
  if (c.action.contains("cancel_after") && !running->done() && running->written() >= c.action.at("cancel_after").get<std::size_t>()) {
    s.cancelExport();
    return Progress::Done;
  }
  if (!running->done()) return Progress::Running;
  s.clearExport();
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::coordinatorSummary(Context& c) {
  StudyController& s = c.model.study();
  if (c.action.contains("study"))
    if (auto st = s.selectStudy(c.action.at("study").get<std::string>()); !st) return tl::unexpected(st.error());
  if (!s.summary()) return fail("ui script: coordinator_summary: no study is selected");
  c.model.event(s.summaryEvent());
  return Progress::Done;
}

// ---------------------------------------------------------------------------------------------
// Imports

// Starts (with "wait": false done at once, else when the import ends; "cancel_at": a stage name
// cancels the import as that stage starts), shown as a user would see it: the window open on the
// form that started it.
ScriptInterpreter::Outcome ScriptInterpreter::importDataset(Context& c) {
  ImportController& im = c.model.imports();
  if (c.first) {
    ImportRequest request;
    request.volumePath = c.action.at("volume").get<std::string>();
    request.labelsPath = c.action.value("labels", "");
    request.namesPath = c.action.value("names", "");
    request.name = c.action.at("name").get<std::string>();
    request.species = c.action.value("species", "human");
    std::optional<ImportStage> cancelAt;
    if (c.action.contains("cancel_at")) {
      cancelAt = parseImportStage(c.action.at("cancel_at").get<std::string>());
      if (!cancelAt) return fail("ui script: import: \"cancel_at\" must be one of " + importStageNames());
    }
    if (auto st = im.start(request, cancelAt); !st) return tl::unexpected(st.error());
    im.windowOpen = true;
    im.form = request;
    if (!c.action.value("wait", true)) return Progress::Done;
  }
  return im.reported() ? Progress::Done : Progress::Running;
}

// Cancels; done once the outcome (cancelled, or done if it was too late) is out.
ScriptInterpreter::Outcome ScriptInterpreter::cancelImport(Context& c) {
  c.model.imports().cancel();
  return c.model.imports().reported() ? Progress::Done : Progress::Running;
}

// Done once the app has taken the dataset (in its next frame).
ScriptInterpreter::Outcome ScriptInterpreter::openImported(Context& c) {
  ImportController& im = c.model.imports();
  if (c.first) {
    if (!im.canOpen()) return fail("ui script: open_imported: no successful import to open");
    im.requestOpen();
    return Progress::Running;
  }
  return im.openRequested() ? Progress::Running : Progress::Done;
}

}  // namespace at::app
