// The UI-script actions' documentation is written from the same registration tables the
// interpreter dispatches through: every dispatched action is documented (with its arguments),
// docs/guide/ui-script-actions.md is exactly that text, and the scripts checked into the
// repository use only documented actions and arguments.
#include <doctest/doctest.h>

#include <filesystem>
#include <map>
#include <regex>
#include <set>

#include <nlohmann/json.hpp>

#include "script/script_interpreter.h"
#include "test_support.h"

using namespace at;
using json = nlohmann::json;
namespace fs = std::filesystem;

namespace {

const fs::path kDocs = fs::path("docs") / "guide" / "ui-script-actions.md";

std::map<std::string, app::ScriptActionDoc> docsByName() {
  std::map<std::string, app::ScriptActionDoc> byName;
  for (const auto& doc : app::ScriptInterpreter::actionDocs()) byName.emplace(doc.name, doc);
  return byName;
}

}  // namespace

TEST_CASE("UI-script actions: each dispatched action is registered once, with its feature, help and arguments") {
  const auto dispatched = app::ScriptInterpreter::actionNames();
  const auto docs = app::ScriptInterpreter::actionDocs();
  std::set<std::string> documented;
  for (const auto& doc : docs) {
    CAPTURE(doc.name);
    CHECK_MESSAGE(documented.insert(doc.name).second, "registered twice");
    CHECK(std::regex_match(doc.name, std::regex("[a-z][a-z_]*")));
    CHECK(!doc.feature.empty());
    CHECK(!doc.featureSummary.empty());
    CHECK(doc.help.size() > 10);
    CHECK(doc.help.back() == '.');
    std::set<std::string> keys;
    for (const auto& arg : doc.arguments) {
      CAPTURE(arg.key);
      CHECK(std::regex_match(arg.key, std::regex("[a-z][a-z_]*\\??")));
      CHECK_MESSAGE(keys.insert(arg.name()).second, "argument named twice");
      CHECK(arg.name() != "do");
      CHECK(!arg.what.empty());
    }
  }
  CHECK(std::set<std::string>(dispatched.begin(), dispatched.end()) == documented);
  CHECK(dispatched.size() == docs.size());
  // The features come as blocks: a feature's actions are listed together.
  std::set<std::string> featuresDone;
  std::string current;
  for (const auto& doc : docs)
    if (doc.feature != current) {
      CHECK_MESSAGE(featuresDone.insert(doc.feature).second, doc.feature);
      current = doc.feature;
    }
  CHECK(featuresDone.size() >= 8);
}

TEST_CASE("UI-script actions: docs/guide/ui-script-actions.md is the registry's text and names every dispatched action") {
  const fs::path path = test::sourceDir() / kDocs;
  REQUIRE(fs::exists(path));
  const std::string file = test::readFile(path);
  CHECK_MESSAGE(file == app::ScriptInterpreter::actionsMarkdown(),
                kDocs.string() << " differs from the actions' registration tables: run scripts/update-ui-script-docs.sh");
  // Independently of how the file was written: its table rows name exactly the dispatched actions.
  std::set<std::string> rows;
  const std::regex row("\\n\\| `([a-z_]+)` \\|");
  for (auto it = std::sregex_iterator(file.begin(), file.end(), row); it != std::sregex_iterator(); ++it) rows.insert((*it)[1]);
  const auto dispatched = app::ScriptInterpreter::actionNames();
  CHECK(rows == std::set<std::string>(dispatched.begin(), dispatched.end()));
}

TEST_CASE("UI-script actions: the repository's scripts use documented actions, their documented arguments, the required ones") {
  const auto byName = docsByName();
  int scripts = 0, actions = 0;
  for (const char* folder : {"docs/screenshots", "bench"})
    for (const auto& entry : fs::recursive_directory_iterator(test::sourceDir() / folder)) {
      if (entry.path().extension() != ".json") continue;
      const json script = json::parse(test::readFile(entry.path()), nullptr, false);
      if (!script.is_object() || !script.contains("actions")) continue;
      ++scripts;
      for (const json& a : script.at("actions")) {
        ++actions;
        const std::string name = a.at("do").get<std::string>();
        CAPTURE(entry.path().string());
        CAPTURE(name);
        const auto doc = byName.find(name);
        REQUIRE_MESSAGE(doc != byName.end(), "undocumented action");
        std::set<std::string> allowed{"do"};
        for (const auto& arg : doc->second.arguments) {
          allowed.insert(arg.name());
          if (!arg.optional()) CHECK_MESSAGE(a.contains(arg.name()), "required argument missing: " << arg.name());
        }
        for (const auto& [key, value] : a.items()) CHECK_MESSAGE(allowed.count(key), "undocumented argument: " << key);
      }
    }
  CHECK(scripts >= 4);
  CHECK(actions > 20);
}

TEST_CASE("UI-script actions: a malformed action's message names the required arguments it leaves out, on one line") {
  int checked = 0;
  for (const auto& doc : app::ScriptInterpreter::actionDocs()) {
    CAPTURE(doc.name);
    const json bare = {{"do", doc.name}};
    const std::string message = app::ScriptInterpreter::malformedActionMessage(bare, doc.name, "type must be string");
    CHECK(message.find('\n') == std::string::npos);
    CHECK(message.rfind("ui script: action " + bare.dump() + ": ", 0) == 0);
    json complete = bare;
    bool required = false;
    for (const auto& arg : doc.arguments) {
      CHECK(message.find(arg.key) != std::string::npos);  // what the action takes
      if (arg.optional()) continue;
      required = true;
      CHECK(message.find("\"" + arg.name() + "\"") != std::string::npos);
      complete[arg.name()] = 1;
    }
    if (!doc.arguments.empty()) CHECK(message.find("desktop --help " + doc.name + ")") != std::string::npos);
    // Given every required argument, the reader's own error is what is wrong.
    const std::string typed = app::ScriptInterpreter::malformedActionMessage(complete, doc.name, "type must be string");
    CHECK(typed.find("missing") == std::string::npos);
    CHECK(typed.find(": type must be string") != std::string::npos);
    checked += required;
  }
  CHECK(checked > 30);
}

TEST_CASE("UI-script actions: `desktop --help-actions` prints the registry, `desktop --help ACTION` one entry") {
  if (!test::requireAppBinary("the desktop's action help")) return;
  const auto all = test::runApp("desktop --help-actions");
  REQUIRE_MESSAGE(all.exitCode == 0, all.err);
  CHECK(all.out == app::ScriptInterpreter::actionsText());
  const auto markdown = test::runApp("desktop --help-actions --markdown");
  REQUIRE(markdown.exitCode == 0);
  CHECK(markdown.out == app::ScriptInterpreter::actionsMarkdown());
  for (const auto& doc : app::ScriptInterpreter::actionDocs()) {
    CAPTURE(doc.name);
    const auto one = test::runApp("desktop --help " + doc.name);
    REQUIRE(one.exitCode == 0);
    CHECK(one.out == *app::ScriptInterpreter::actionText(doc.name));
    CHECK(one.out.find(doc.help) != std::string::npos);
    for (const auto& arg : doc.arguments) CHECK(one.out.find("      " + arg.name()) != std::string::npos);
  }
  const auto unknown = test::runApp("desktop --help no_such_action");
  CHECK(unknown.exitCode == 2);
  CHECK(unknown.err.find("no UI-script action 'no_such_action'") != std::string::npos);
}
