// The UI script's study actions: a participant's screens and the coordinator's window, through the
// StudyController commands their widgets call.
#include "script_answers.h"
#include "script_interpreter.h"

namespace at::app {

using json = nlohmann::json;

ScriptInterpreter::Feature ScriptInterpreter::studyActions() {
  using S = ScriptInterpreter;
  const ScriptArgument study{"study?", "a study id (default: the one selected)"};
  const ScriptArgument timeout{"timeout_ms?", "how long to wait for the screen (default 60000)"};
  return {"studies",
          "rating studies: the participant's screens and the coordinator",
          {
              {"study_start", {{"study", "the study id"}, {"participant", "the participant's code"}, {"group", "their group"}, timeout},
               "Starts a participant; done once the first screen is drawn.", &S::studyStart},
              {"study_toggle", {{"side?", "the side to show (default: the other one)"}}, "Toggles the side shown.", &S::study},
              {"study_rate", {{"item", "the rating item"}, {"rating", "the rating"}, {"timeout_ms?", "default 60000"}},
               "Rates, once the side on screen has been drawn at full quality.", &S::study},
              {"study_comment", {{"text", "the comment"}}, "Sets the trial's comment.", &S::study},
              {"study_next", {timeout}, "The next trial; done once its screen is drawn.", &S::study},
              {"study_close", {}, "Closes the participant's screens.", &S::study},
              {"coordinator_open", {study}, "Opens the coordinator's window (on the study).", &S::coordinatorOpen},
              {"coordinator_export", {study, {"out", "the folder to export into"}, {"cancel_after?", "press Cancel once this many files are written"}},
               "Exports the study's ratings; done once the last file is written.", &S::coordinatorExport},
              {"coordinator_summary", {study}, "Reports the study's summary as the window shows it.", &S::coordinatorSummary},
          }};
}

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

}  // namespace at::app
