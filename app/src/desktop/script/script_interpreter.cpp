// The loop: each frame runs the queued actions through the handlers the features register.
#include "script/script_interpreter.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <utility>

#include "core/atomic_file.h"

namespace at::app {

using json = nlohmann::json;

const std::vector<ScriptInterpreter::Feature>& ScriptInterpreter::features() {
  static const std::vector<Feature> all = {viewActions(),    outputActions(),  lessonActions(), examActions(),
                                           analyticsActions(), expertActions(), studyActions(),  importActions(),
                                           segmentActions(),   courseActions()};
  return all;
}

// Built once from the features' tables; a name registered twice stops the program at its first
// script (a programming error the registry test also names).
const std::map<std::string, ScriptInterpreter::Handler>& ScriptInterpreter::handlers() {
  static const std::map<std::string, Handler> table = [] {
    std::map<std::string, Handler> t;
    for (const Feature& feature : features())
      for (const Action& action : feature.actions)
        if (!t.emplace(action.name, action.handler).second) {
          std::fprintf(stderr, "ui script: action '%s' is registered twice (feature %s)\n", action.name, feature.name);
          std::abort();
        }
    return t;
  }();
  return table;
}

std::vector<std::string> ScriptInterpreter::actionNames() {
  std::vector<std::string> names;
  for (const auto& [name, handler] : handlers()) names.push_back(name);
  return names;
}

// ---------------------------------------------------------------------------------------------
// The loop

Result<ScriptInterpreter> ScriptInterpreter::load(const std::string& path, std::optional<std::string> finalScreenshot) {
  if (auto ok = checkRegularFile(path, path); !ok) return tl::unexpected(ok.error());
  std::ifstream in(path);
  if (!in) return fail(ErrorKind::NotFound, path + ": cannot open the UI script");
  json script;
  try {
    in >> script;
  } catch (const json::exception& e) {
    return fail(path + ": not JSON (" + e.what() + ")");
  }
  if (!script.is_object() || !script.contains("actions") || !script["actions"].is_array())
    return fail(path + ": a UI script is an object with an \"actions\" list");
  return ScriptInterpreter(script["actions"].get<std::vector<json>>(), std::move(finalScreenshot));
}

ScriptInterpreter::ScriptInterpreter(std::vector<json> actions, std::optional<std::string> finalScreenshot)
    : actions_(actions.begin(), actions.end()), finalScreenshot_(std::move(finalScreenshot)) {}

void ScriptInterpreter::finish(int status) {
  status_ = status;
  finished_ = true;
}

void ScriptInterpreter::screenshotFailed(const std::string& why, DesktopModel& model) {
  model.message(why);
  finish(1);
}

void ScriptInterpreter::step(DesktopModel& model, ScriptHost& host, Clock::time_point now) {
  if (finished_ || host.screenshotPending()) return;
  while (!actions_.empty()) {
    const json a = actions_.front();  // a copy: an action may add actions (hover_sweep)
    if (!a.is_object() || !a.contains("do") || !a["do"].is_string()) {
      model.message("ui script: every action must be an object with a \"do\" string, got " + a.dump());
      return finish(2);
    }
    const std::string what = a["do"];
    const auto handler = handlers().find(what);
    if (handler == handlers().end()) {
      model.message("ui script: unknown action \"" + what + "\"");
      return finish(2);
    }
    const bool first = !begun_;
    if (first) {
      begun_ = true;
      actionStart_ = now;
    }
    Context context{model, host, a, first, msBetween(actionStart_, now), actionStart_};
    Outcome outcome = Progress::Done;
    try {
      outcome = (this->*handler->second)(context);
    } catch (const std::exception& e) {  // nlohmann's type and range errors: a malformed action
      outcome = fail(malformedActionMessage(a, what, e.what()));
    }
    if (!outcome) {
      model.message(outcome.error().message);
      return finish(outcome.error().kind == ErrorKind::Unavailable ? 1 : 2);
    }
    if (*outcome == Progress::Running) return;
    if (!actions_.empty() && actions_.front() == a) actions_.pop_front();  // hover_sweep replaced itself
    begun_ = false;
    if (host.screenshotPending()) return;  // the frame draws it first
  }
  // All actions done: the final screenshot once the view has settled.
  if (finalScreenshot_) {
    if (!begun_) {
      begun_ = true;
      actionStart_ = now;
    }
    if (!model.settled() && msBetween(actionStart_, now) < 120000) return;
    host.requestScreenshot(*std::exchange(finalScreenshot_, std::nullopt));
    return;
  }
  finish(status_);
}

}  // namespace at::app
