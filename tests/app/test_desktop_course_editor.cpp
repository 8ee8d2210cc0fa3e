// The desktop's course editor, driven headless through the UI script as an instructor would use
// it: a course made on the phantom on screen (show steps captured from the view, questions of
// several kinds, steps duplicated, moved, deleted and previewed, live validation naming the field),
// saved, exported as a package, opened in another database with Open course…, and played there.
#include <doctest/doctest.h>

#include <algorithm>

#include "cli_checks.h"
#include "db/preset_store.h"
#include "headless_desktop.h"
#include "render/preset.h"

using namespace at;
namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

test::HeadlessOptions on(const fs::path& db) {
  test::HeadlessOptions options;
  options.dataset = "phantom:64";
  options.db = db;
  return options;
}

json lastEdit(const test::HeadlessRun& run) {
  const auto edits = test::eventsOf(run, "course_edited");
  REQUIRE_FALSE(edits.empty());
  return edits.back();
}

std::vector<std::string> stepKinds(const json& edit) {
  std::vector<std::string> kinds;
  for (const json& s : edit["steps"]) kinds.push_back(s["kind"].get<std::string>() + ":" + s.value("structure", s.value("target", "")));
  return kinds;
}

}  // namespace

TEST_CASE("CourseEditor_ScriptedAuthoring_SavesExportsAndPlaysInAnotherDatabase") {
  test::TempDir author("at-author"), student("at-student");
  const fs::path package = author / "ear_quiz.atcourse";
  const json script = {{"actions", json::array({
      {{"do", "course_new"}, {"id", "ear_quiz"}, {"title", "Ear quiz"}},
      {{"do", "select"}, {"structure", "cochlea"}},
      {{"do", "view"}, {"value", "superior"}},
      {{"do", "t"}, {"value", 0.35}},
      {{"do", "course_show"}, {"title", "The cochlea"}, {"text", "The coiled part of the inner ear."}},
      {{"do", "course_question"}, {"question", {{"kind", "name"}, {"prompt", "Name it."}, {"target", "cochlea"},
                                               {"synonyms", {"snail"}}}}},
      {{"do", "course_question"}, {"question", {{"kind", "identify"}, {"prompt", "Which is highlighted?"}, {"target", "stapes"}}}},
      // A locate question asked on a neighbour's view.
      {{"do", "select"}, {"structure", "vestibule"}},
      {{"do", "course_question"}, {"scene", true},
       {"question", {{"kind", "locate"}, {"prompt", "Click the cochlea."}, {"target", "cochlea"}, {"tolerance_mm", 0.5}}}},
      // A mistake, flagged by its field path, then removed.
      {{"do", "course_question"}, {"question", {{"kind", "name"}, {"prompt", "Name it."}, {"target", "pancreas"}}}},
      {{"do", "course_step"}, {"op", "delete"}, {"index", 4}},
      {{"do", "course_step"}, {"op", "duplicate"}, {"index", 1}},
      {{"do", "course_step"}, {"op", "move"}, {"index", 2}, {"to", 4}},
      {{"do", "course_step"}, {"op", "delete"}, {"index", 4}},
      {{"do", "course_step"}, {"op", "preview"}, {"index", 0}},
      {{"do", "course_lesson"}, {"title", "Middle ear"}, {"prerequisites", {"ear_quiz.lesson_1"}}},
      {{"do", "select"}, {"structure", "malleus"}},
      {{"do", "course_show"}, {"title", "The malleus"}, {"text", "The hammer."}},
      {{"do", "course_save"}},
      {{"do", "course_export"}, {"path", package.string()}},
  })}};
  auto run = test::runHeadless(script, on(author / "a.db"));
  CAPTURE(run.messages);
  REQUIRE(run.exitCode == 0);

  const auto edits = test::eventsOf(run, "course_edited");
  // The bad target was named by its path while it was there …
  const auto flagged = std::find_if(edits.begin(), edits.end(), [](const json& e) {
    for (const json& p : e["problems"])
      if (p.get<std::string>() == "lessons[0].steps[4].question.target: no structure 'pancreas' in dataset 'phantom'") return true;
    return false;
  });
  CHECK(flagged != edits.end());
  // … and the first lesson ends as show, name, identify, locate (the duplicate moved, then deleted).
  json firstLesson;
  for (const json& e : edits)
    if (e["lesson"] == 0 && e["lessons"].size() == 1) firstLesson = e;
  CHECK(stepKinds(firstLesson) == std::vector<std::string>{"show:cochlea", "name:cochlea", "identify:stapes", "locate:cochlea"});
  CHECK(firstLesson["problems"].empty());
  const json last = lastEdit(run);
  CHECK(last["lessons"] == json({"ear_quiz.lesson_1", "ear_quiz.middle_ear"}));
  CHECK(last["problems"].empty());
  const auto saved = test::eventsOf(run, "course_saved");
  REQUIRE(saved.size() >= 1);
  CHECK(saved.front()["outcome"] == "added");
  CHECK(test::eventsOf(run, "course_exported").size() == 1);

  // The captured show step's preset keeps the view's t and named view.
  {
    auto database = db::openDatabase((author / "a.db").string());
    REQUIRE(database);
    auto stored = db::findPreset(*database, "ear_quiz.lesson_1.show_1");
    REQUIRE(stored);
    REQUIRE(*stored);
    auto preset = render::parsePreset((*stored)->json, "stored");
    REQUIRE(preset);
    CHECK(preset->t == doctest::Approx(0.35));
    CHECK(preset->view == std::optional<std::string>("superior"));
  }

  // Open course… in the student's database, then play the first lesson in the terminal.
  const json open = {{"actions", json::array({{{"do", "course_open_package"}, {"path", package.string()}},
                                              {{"do", "lessons"}, {"course", "ear_quiz"}}})}};
  auto opened = test::runHeadless(open, on(student / "s.db"));
  CAPTURE(opened.messages);
  REQUIRE(opened.exitCode == 0);
  const auto imported = test::eventsOf(opened, "course_imported");
  REQUIRE(imported.size() == 1);
  CHECK(imported[0]["dataset_action"] == "built in");
  const std::string answers = R"({"text": "snail"})" "\n" R"({"choice": 0})" "\n" R"({"point_mm": [0, 0, 0]})" "\n";
  auto played = test::runApp("play ear_quiz.lesson_1 --user erin --new-user --no-views --db '" + (student / "s.db").string() + "'",
                             answers);
  CAPTURE(played.err);
  CHECK(played.exitCode == 0);
  CHECK(played.out.find("The coiled part of the inner ear.") != std::string::npos);
  CHECK(played.out.find("Lesson finished") != std::string::npos);
}

TEST_CASE("CourseEditor_SavingAChangedStoredCourse_StoresTheNextVersion") {
  test::TempDir dir;
  const json script = {{"actions", json::array({
      {{"do", "course_open"}, {"course", "temporal_bone"}},
      {{"do", "course_step"}, {"op", "delete"}, {"index", 0}},
      {{"do", "course_save"}},
      {{"do", "course_save"}},
  })}};
  auto run = test::runHeadless(script, on(dir / "t.db"));
  CAPTURE(run.messages);
  REQUIRE(run.exitCode == 0);
  const auto saved = test::eventsOf(run, "course_saved");
  REQUIRE(saved.size() == 2);
  CHECK(saved[0]["outcome"] == "updated");
  CHECK(saved[1]["outcome"] == "unchanged");
  CHECK(saved[0]["version"].get<int>() == saved[1]["version"].get<int>());
  CHECK(saved[0]["version"].get<int>() >= 3);

  // A save that cannot be made ends the script with the problem on one line.
  const json bad = {{"actions", json::array({
      {{"do", "course_new"}, {"id", "empty_one"}},
      {{"do", "course_save"}},
  })}};
  auto refused = test::runHeadless(bad, on(dir / "t.db"));
  CHECK(refused.exitCode == 2);
  CHECK(refused.messages.find("course 'empty_one' cannot be saved: lessons[0].steps") != std::string::npos);
}
