// The UI script's analytics action: the commands of the Class analytics window's widgets.
#include "script_answers.h"
#include "script_interpreter.h"

namespace at::app {

ScriptInterpreter::Feature ScriptInterpreter::analyticsActions() {
  using S = ScriptInterpreter;
  return {"analytics",
          "the Class analytics window",
          {
              {"analytics",
               {{"course?", "the course whose class to show (needed unless close)"}, {"group?", "one group of the class"},
                {"tab?", "structures, missed, students or lessons"}, {"close?", "true: close the window"}},
               "Opens the Class analytics window on the course's class, read from the database (or closes it).",
               &S::analytics},
          }};
}

// {"do": "analytics", "course": ID, "group": G, "tab": T}: opens the Class analytics window on the
// class of the course (of one group when given), read from the database [analytics], on tab T
// (structures, missed, students or lessons; default: as it was); {"do": "analytics", "close":
// true} closes the window.
ScriptInterpreter::Outcome ScriptInterpreter::analytics(Context& c) {
  AnalyticsController& a = c.model.analytics();
  if (c.action.value("close", false)) {
    a.windowOpen = false;
    return Progress::Done;
  }
  std::optional<AnalyticsController::Tab> tab;
  if (c.action.contains("tab") && !(tab = AnalyticsController::parseTab(c.action.at("tab").get<std::string>())))
    return actionError(c.action, Error{ErrorKind::Invalid, "tab must be structures, missed, students or lessons"});
  std::optional<std::string> group;
  if (c.action.contains("group")) group = c.action.at("group").get<std::string>();
  if (auto st = a.load(c.action.at("course").get<std::string>(), group); !st)
    return actionError(c.action, st.error());
  a.windowOpen = true;
  if (tab) a.requestedTab = tab;
  return Progress::Done;
}

}  // namespace at::app
