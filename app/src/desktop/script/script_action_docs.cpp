// The UI-script actions' documentation, written from the features' registration tables (the same
// tables the interpreter dispatches through): `desktop --help-actions`, `desktop --help ACTION` and
// docs/guide/ui-script-actions.md.
#include <sstream>

#include "script/script_interpreter.h"

namespace at::app {

namespace {

// "structure, t?" — the argument keys as the action's one-line form shows them.
std::string argumentKeys(const ScriptActionDoc& a) {
  std::string keys;
  for (const ScriptArgument& arg : a.arguments) keys += (keys.empty() ? "" : ", ") + arg.key;
  return keys;
}

// '|' would end a Markdown table cell.
std::string cell(const std::string& text) {
  std::string out;
  for (char ch : text) out += ch == '|' ? std::string("\\|") : std::string(1, ch);
  return out;
}

void writeEntry(std::ostringstream& out, const ScriptActionDoc& a) {
  out << "  " << a.name;
  if (!a.arguments.empty()) out << " {" << argumentKeys(a) << "}";
  out << "\n      " << a.help << "\n";
  for (const ScriptArgument& arg : a.arguments)
    out << "      " << arg.name() << (arg.optional() ? " (optional)" : "") << ": " << arg.what << "\n";
}

}  // namespace

std::vector<ScriptActionDoc> ScriptInterpreter::actionDocs() {
  std::vector<ScriptActionDoc> docs;
  for (const Feature& feature : features())
    for (const Action& action : feature.actions)
      docs.push_back({feature.name, feature.summary, action.name, action.arguments, action.help});
  return docs;
}

std::string ScriptInterpreter::actionsText() {
  std::ostringstream out;
  out << "UI-script actions ({\"actions\": [{\"do\": NAME, ARGUMENT: VALUE, ...}, ...]}), by feature;\n"
         "arguments marked optional may be left out.\n";
  std::string feature;
  for (const ScriptActionDoc& a : actionDocs()) {
    if (a.feature != feature) {
      feature = a.feature;
      out << "\n" << a.feature << ": " << a.featureSummary << "\n";
    }
    writeEntry(out, a);
  }
  return out.str();
}

std::optional<std::string> ScriptInterpreter::actionText(const std::string& name) {
  for (const ScriptActionDoc& a : actionDocs())
    if (a.name == name) {
      std::ostringstream out;
      out << a.feature << ": " << a.featureSummary << "\n";
      writeEntry(out, a);
      return out.str();
    }
  return std::nullopt;
}

std::string ScriptInterpreter::malformedActionMessage(const nlohmann::json& action, const std::string& name,
                                                      const std::string& error) {
  std::string missing, takes;
  for (const ScriptActionDoc& a : actionDocs()) {
    if (a.name != name) continue;
    takes = argumentKeys(a);
    for (const ScriptArgument& arg : a.arguments)
      if (!arg.optional() && !(action.is_object() && action.contains(arg.name())))
        missing += (missing.empty() ? "\"" : ", \"") + arg.name() + "\"";
  }
  std::string out = "ui script: action " + action.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace) + ": " +
                    (missing.empty() ? error : missing + " missing");
  if (!takes.empty()) out += " (" + name + " takes " + takes + ": desktop --help " + name + ")";
  return out;
}

std::string ScriptInterpreter::actionsMarkdown() {
  std::ostringstream out;
  out << "# UI-script actions\n\n"
         "<!-- Written by `anatomy-tutor desktop --help-actions --markdown` from the actions' registration\n"
         "     tables (app/src/desktop/*/script_actions_*.cpp); tests/app/test_script_actions_documented.cpp\n"
         "     fails when this file differs: regenerate it with scripts/update-ui-script-docs.sh. -->\n\n"
         "`anatomy-tutor desktop --ui-script FILE.json` replays `{\"actions\": [{\"do\": NAME, ...}, ...]}`, one\n"
         "action after another, through the commands the desktop's widgets call; the events they emit are\n"
         "the script's output (one JSON line each). An action that waits holds the next. A malformed or\n"
         "failing action ends the script with status 2, a timeout with status 1. Arguments marked `?`\n"
         "may be left out. `anatomy-tutor desktop --help ACTION` prints one action.\n";
  std::string feature;
  for (const ScriptActionDoc& a : actionDocs()) {
    if (a.feature != feature) {
      feature = a.feature;
      out << "\n## " << a.feature << " — " << a.featureSummary << "\n\n"
          << "| action | arguments | what it does |\n|---|---|---|\n";
    }
    std::string args;
    for (const ScriptArgument& arg : a.arguments) args += (args.empty() ? "" : "<br>") + ("`" + arg.key + "` " + cell(arg.what));
    out << "| `" << a.name << "` | " << args << " | " << cell(a.help) << " |\n";
  }
  out << "\n[Back to the desktop guide](desktop.md)\n";
  return out.str();
}

}  // namespace at::app
