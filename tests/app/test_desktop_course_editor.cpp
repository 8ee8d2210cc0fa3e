// The desktop's course editor, driven headless through the UI script as an instructor would use
// it: a course made on the phantom on screen (show steps captured from the view, questions of
// several kinds, steps duplicated, moved, deleted and previewed, live validation naming the field),
// saved, exported as a package, opened in another database with Open course…, and played there;
// and a locate question's view check, which runs on the editor's worker while frames go on.
#include <doctest/doctest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <thread>

#include "cli_checks.h"
#include "course_views.h"
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
      // A locate question asked on a neighbour's view (from the front: from above the facial nerve
      // hides the cochlea's centre, and the editor refuses it).
      {{"do", "select"}, {"structure", "vestibule"}},
      {{"do", "view"}, {"value", "anterior"}},
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

// "Capture current view" keeps where the author left the camera (orbited and zoomed away from the
// named view) and the clipping plane; the editor's preview and a student's lesson replay both.
TEST_CASE("CourseEditor_ShowStep_CapturesAndReplaysAFreeCameraAndTheClippingPlane") {
  test::TempDir dir;
  struct Seen {
    render::Camera camera;
    app::ClipSettings clip;
  };
  std::vector<Seen> frames;
  test::HeadlessOptions options = on(dir / "c.db");
  options.drawPanels = [&](app::DesktopModel& model) { frames.push_back({model.explore().camera(), model.explore().clip()}); };
  const json wait = {{"do", "wait"}, {"ms", 20}};
  const json script = {{"actions", json::array({
      {{"do", "course_new"}, {"id", "clip_tour"}, {"title", "Clip tour"}},
      {{"do", "select"}, {"structure", "cochlea"}},
      {{"do", "view"}, {"value", "superior"}},
      {{"do", "orbit"}, {"azimuth", 35}, {"elevation", -20}},
      {{"do", "zoom"}, {"factor", 1.6}},
      {{"do", "clip"}, {"on", true}, {"axis", 1}, {"flip", true}, {"offset", 1.5}},
      wait,
      {{"do", "course_show"}, {"title", "Cut open"}, {"text", "The cochlea from above and behind, cut."}},
      // The author looks elsewhere, unclipped …
      {{"do", "view"}, {"value", "lateral_left"}},
      {{"do", "clip"}, {"on", false}},
      wait,
      // … and previews the step: the captured camera and plane come back.
      {{"do", "course_step"}, {"op", "preview"}, {"index", 0}},
      wait,
      {{"do", "course_save"}},
  })}};
  auto run = test::runHeadless(script, options);
  CAPTURE(run.messages);
  REQUIRE(run.exitCode == 0);
  REQUIRE(frames.size() >= 3);

  // The authored view (the last frame before course_show) …
  auto session = app::LearningSession::open((dir / "c.db").string());
  REQUIRE(session);
  auto course = (*session)->curriculum().course("clip_tour");
  REQUIRE_MESSAGE(course, (course ? "" : course.error().message));
  const lessons::ShowStep& show = course->lessons[0].steps[0].show;
  REQUIRE(show.camera.has_value());
  REQUIRE(show.clip.has_value());
  CHECK((show.view == lessons::CameraView::Superior));
  CHECK(show.clip->normal == Vec3{0, -1, 0});
  // … is not the named view's framing: orbited away from straight down, closer.
  CHECK(std::abs(show.camera->look[2] + 1) > 0.05);
  const render::Camera replayed = frames.back().camera;
  CHECK(replayed.eye()[0] == doctest::Approx(app::cameraOf(*show.camera).eye()[0]).epsilon(1e-6));
  CHECK(replayed.eye()[1] == doctest::Approx(app::cameraOf(*show.camera).eye()[1]).epsilon(1e-6));
  CHECK(replayed.eye()[2] == doctest::Approx(app::cameraOf(*show.camera).eye()[2]).epsilon(1e-6));
  CHECK(replayed.up()[2] == doctest::Approx(show.camera->up[2]).epsilon(1e-6));
  CHECK(replayed.distanceMm == doctest::Approx(show.camera->distanceMm));
  const app::ClipSettings clip = frames.back().clip;
  CHECK(clip.on);
  CHECK(clip.axis == 1);
  CHECK(clip.flip);
  CHECK(clip.offsetMm == doctest::Approx(1.5));
  // The lateral_left frames between differ (the replay is not the state left over).
  const auto elsewhere = std::find_if(frames.begin(), frames.end(), [](const Seen& f) { return !f.clip.on && f.camera.forward()[0] < -0.99; });
  CHECK(elsewhere != frames.end());

  // A student's lesson in the desktop starts on the same camera and plane.
  frames.clear();
  const json play = {{"actions", json::array({{{"do", "view"}, {"value", "anterior"}},
                                              {{"do", "lessons"}, {"course", "clip_tour"}},
                                              {{"do", "lesson"}, {"course", "clip_tour"}, {"lesson", "clip_tour.lesson_1"}},
                                              wait})}};
  auto student = test::runHeadless(play, options);
  CAPTURE(student.messages);
  REQUIRE(student.exitCode == 0);
  REQUIRE_FALSE(frames.empty());
  CHECK(frames.back().camera.distanceMm == doctest::Approx(show.camera->distanceMm));
  CHECK(frames.back().camera.forward()[2] == doctest::Approx(show.camera->look[2]).epsilon(1e-6));
  CHECK(frames.back().clip.on);
  CHECK(frames.back().clip.flip);
}

// The preview of a question step hides structure names as the lesson does (the explore panel draws
// none while DesktopModel::namesHidden()), until the author selects another structure; a show
// step's preview keeps them.
TEST_CASE("CourseEditor_PreviewOfAQuestion_HidesNamesAsTheStudentSeesIt") {
  test::TempDir dir;
  struct Seen {
    std::string selected;
    std::optional<std::size_t> previewing;
    bool namesHidden = false;
  };
  std::vector<Seen> frames;
  test::HeadlessOptions options = on(dir / "c.db");
  options.drawPanels = [&](app::DesktopModel& model) {
    const auto& p = model.courseEditor().previewing();
    const Structure* selected = model.dataset().findStructureByLabel(model.explore().selected());
    frames.push_back({selected ? selected->id : "", p ? std::optional<std::size_t>(p->step) : std::nullopt, model.namesHidden()});
  };
  const json wait = {{"do", "wait"}, {"ms", 20}};
  const json script = {{"actions", json::array({
      {{"do", "course_new"}, {"id", "names"}},
      {{"do", "select"}, {"structure", "cochlea"}},
      {{"do", "course_show"}, {"title", "The cochlea"}, {"text", "Coiled."}},
      {{"do", "course_question"}, {"question", {{"kind", "name"}, {"prompt", "Name it."}, {"target", "stapes"}}}},
      {{"do", "course_step"}, {"op", "preview"}, {"index", 1}},
      wait,
      {{"do", "select"}, {"structure", "vestibule"}},
      wait,
      {{"do", "course_step"}, {"op", "preview"}, {"index", 1}},
      wait,
      {{"do", "course_step"}, {"op", "preview"}, {"index", 0}},
      wait,
  })}};
  auto run = test::runHeadless(script, options);
  CAPTURE(run.messages);
  REQUIRE(run.exitCode == 0);
  const auto previews = test::eventsOf(run, "course_preview");
  REQUIRE(previews.size() == 3);
  CHECK(previews[0]["names_hidden"] == true);
  CHECK(previews[0]["structure"] == "stapes");
  CHECK(previews[2]["names_hidden"] == false);

  // Frames of the question's preview hide names; once vestibule is selected they show again; the
  // second preview hides them again; the show step's does not.
  std::vector<std::string> phases;
  for (const Seen& f : frames) {
    const std::string phase = f.selected + (f.namesHidden ? ":hidden" : ":shown");
    if (phases.empty() || phases.back() != phase) phases.push_back(phase);
  }
  CAPTURE(phases);
  const std::vector<std::string> tail(phases.end() - std::min<std::ptrdiff_t>(4, std::ptrdiff_t(phases.size())), phases.end());
  CHECK(tail == std::vector<std::string>{"stapes:hidden", "vestibule:shown", "stapes:hidden", "cochlea:shown"});
  CHECK(frames.back().previewing == std::optional<std::size_t>(0));
}

// The default "Lesson 1" an author leaves empty (working in a lesson added after it) does not
// block Save: it is left out of the stored course; a course with no step at all still cannot be saved.
TEST_CASE("CourseEditor_AnEmptyDefaultLesson_DoesNotBlockSave") {
  test::TempDir dir;
  const json script = {{"actions", json::array({
      {{"do", "course_new"}, {"id", "inner_ear"}, {"title", "Inner ear"}},
      {{"do", "course_lesson"}, {"title", "Cochlea"}},
      {{"do", "select"}, {"structure", "cochlea"}},
      {{"do", "course_show"}, {"title", "The cochlea"}, {"text", "The coiled part of the inner ear."}},
      {{"do", "course_save"}},
  })}};
  auto run = test::runHeadless(script, on(dir / "t.db"));
  CAPTURE(run.messages);
  REQUIRE(run.exitCode == 0);
  const auto saved = test::eventsOf(run, "course_saved");
  REQUIRE(saved.size() == 1);
  CHECK(saved[0]["outcome"] == "added");
  auto session = app::LearningSession::open((dir / "t.db").string());
  REQUIRE(session);
  auto course = (*session)->curriculum().course("inner_ear");
  REQUIRE(course);
  REQUIRE(course->lessons.size() == 1);
  CHECK(course->lessons[0].title == "Cochlea");
  CHECK(course->lessons[0].steps.size() == 1);

  // `desktop --course inner_ear` opens the stored course (not a file of the course folder) on its
  // dataset; an id no one has is still refused, naming it.
  test::HeadlessOptions start = on(dir / "t.db");
  start.dataset.clear();
  start.course = "inner_ear";
  const json nothing = {{"actions", json::array()}};
  auto opened = test::runHeadless(nothing, start);
  CAPTURE(opened.messages);
  CHECK(opened.exitCode == 0);
  start.course = "no_such_course";
  auto refused = test::runHeadless(nothing, start);
  CHECK(refused.exitCode != 0);
  CHECK(refused.messages.find("no_such_course") != std::string::npos);
}

// An instructor captures a locate question in a view that draws nothing but the highlighted region
// (the bare view): the cochlea lies behind blackness, so the editor refuses it, names why, and the
// draft is unchanged; in the WDT view of the same region it is added.
TEST_CASE("CourseEditor_LocateQuestionInAViewThatDrawsNothingWhereItsTargetIs_IsRefused") {
  test::TempDir author("at-author");
  const json locate = {{"do", "course_question"},
                       {"scene", true},
                       {"question", {{"kind", "locate"}, {"prompt", "Click the cochlea."}, {"target", "cochlea"}}}};
  const json bare = {{"actions", json::array({
      {{"do", "course_new"}, {"id", "blank_quiz"}, {"title", "Blank quiz"}},
      {{"do", "select"}, {"structure", "vestibule"}},
      {{"do", "view"}, {"value", "anterior"}},
      {{"do", "course_question"}, {"question", {{"kind", "name"}, {"prompt", "Name it."}, {"target", "vestibule"}}}},
      {{"do", "mode"}, {"value", "bare"}},
      locate,
  })}};
  auto refused = test::runHeadless(bare, on(author / "a.db"));
  CAPTURE(refused.messages);
  CHECK(refused.exitCode != 0);
  CHECK(refused.messages.find("question not added: the cochlea is not drawn in its view (anterior, region vestibule") !=
        std::string::npos);
  // The draft still ends with the name question: nothing was added.
  CHECK(stepKinds(lastEdit(refused)) == std::vector<std::string>{"name:vestibule"});

  json wdt = bare;
  wdt["actions"][4]["value"] = "wdt";
  auto added = test::runHeadless(wdt, on(author / "b.db"));
  CAPTURE(added.messages);
  CHECK(added.exitCode == 0);
  CHECK(stepKinds(lastEdit(added)) == std::vector<std::string>{"name:vestibule", "locate:cochlea"});
}

namespace {

// A locate check whose work waits until the test releases it (or its cancel is set, or 5 s pass),
// then answers `answerable`: the check a CourseEditor is given, standing in for the view check
// that takes seconds on a real CT. It notes the thread the work ran on and whether it was
// released in time.
struct LatchedCheck {
  std::mutex mutex;
  std::condition_variable changed;
  bool released = false;
  bool answerable = true;
  int calls = 0;
  bool sawCancel = false;
  bool timedOut = false;
  std::thread::id workThread;

  void release() {
    std::lock_guard lock(mutex);
    released = true;
    changed.notify_all();
  }
  app::CourseEditor::LocateViewCheck check() {
    return [this](const quiz::Question& question, const lessons::QuestionScene&, const render::Preset&) {
      ++calls;
      return [this, id = question.id](const std::atomic<bool>& cancel) -> Result<app::LocateCheck> {
        std::unique_lock lock(mutex);
        workThread = std::this_thread::get_id();
        const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
        while (!released && !cancel) {
          if (changed.wait_until(lock, std::min(deadline, std::chrono::steady_clock::now() + std::chrono::milliseconds(5))) ==
                  std::cv_status::timeout &&
              std::chrono::steady_clock::now() >= deadline) {
            timedOut = true;
            break;
          }
        }
        sawCancel = cancel;
        app::LocateCheck c;
        c.questionId = id;
        c.answerable = answerable;
        if (!answerable) c.problem = "the cochlea is not drawn in its view (test)";
        return c;
      };
    };
  }
};

struct EditorOnPhantom {
  test::TempDir dir{"at-async-check"};
  std::unique_ptr<app::LearningSession> session;
  render::PresetLibrary library{test::sourceDir() / "data" / "presets"};
  std::vector<json> events;
  std::unique_ptr<app::CourseEditor> editor;

  explicit EditorOnPhantom(app::CourseEditor::LocateViewCheck check) {
    auto opened = app::LearningSession::open((dir / "a.db").string());
    REQUIRE_MESSAGE(opened, (opened ? "" : opened.error().message));
    session = std::move(*opened);
    editor = std::make_unique<app::CourseEditor>(
        *session, library, [this](json e) { events.push_back(std::move(e)); },
        [](const lessons::QuestionScene&, const std::optional<render::Preset>&) {}, std::move(check));
    REQUIRE(editor->newCourse("async_quiz", "Async quiz", "phantom"));
    quiz::Question name;
    name.kind = quiz::QuestionKind::Name;
    name.prompt = "Name it.";
    name.target = "vestibule";
    REQUIRE(editor->addQuestion(name, std::nullopt));
  }
  static quiz::Question locate(const std::string& target) {
    quiz::Question q;
    q.kind = quiz::QuestionKind::Locate;
    q.prompt = "Click the " + target + ".";
    q.target = target;
    return q;
  }
  static app::CourseEditor::Capture scene() {
    app::CourseEditor::Capture c;
    c.structure = "vestibule";
    c.preset.id = "vestibule_wdt";
    c.view = lessons::CameraView::Anterior;
    return c;
  }
  std::vector<std::string> steps() const {
    std::vector<std::string> out;
    for (const lessons::Step& s : editor->draft().lessons[editor->lessonIndex()].steps)
      out.push_back(std::string(quiz::toString(s.question.kind)) + ":" + s.question.target);
    return out;
  }
  // Polls as the frames do until the check's result is applied (at most 5 s).
  void pollUntilChecked() {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (editor->checking() && std::chrono::steady_clock::now() < deadline) {
      editor->poll();
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    REQUIRE_FALSE(editor->checking());
  }
};

double msSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

// The locate check runs on the editor's worker: addQuestion returns while the check is still
// blocked (a synchronous check would hold it until the latch's 5 s ran out), the frames' poll()
// returns at once meanwhile, the draft is unchanged and stays editable (adding a step is refused so
// that the order holds), and once released the question asked is appended as the synchronous code
// appended it; a refused one changes nothing and says why.
TEST_CASE("CourseEditor_LocateQuestionBeingChecked_DoesNotBlockTheUiThreadAndIsAddedWhenTheCheckEnds") {
  LatchedCheck latch;
  EditorOnPhantom on(latch.check());
  app::CourseEditor& editor = *on.editor;

  const auto asked = std::chrono::steady_clock::now();
  REQUIRE(editor.addQuestion(EditorOnPhantom::locate("cochlea"), EditorOnPhantom::scene()));
  CHECK(msSince(asked) < 1000);
  CHECK(latch.calls == 1);
  REQUIRE(editor.checking());
  CHECK_FALSE(test::eventsOf(on.events, "course_question_checking").empty());

  // Frames go on: each poll returns promptly while the check waits; nothing is added yet.
  for (int frame = 0; frame < 20; ++frame) {
    const auto start = std::chrono::steady_clock::now();
    editor.poll();
    CHECK(msSince(start) < 50);
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  CHECK(editor.checking());
  CHECK(on.steps() == std::vector<std::string>{"name:vestibule"});
  // The draft stays editable; adding another step waits for the check's end.
  CHECK(editor.setTitle("Renamed while checking", ""));
  const auto second = editor.addQuestion(EditorOnPhantom::locate("stapes"), EditorOnPhantom::scene());
  REQUIRE_FALSE(second);
  CHECK((second.error().kind == ErrorKind::Conflict));
  CHECK(latch.calls == 1);

  latch.release();
  on.pollUntilChecked();
  CHECK_FALSE(latch.timedOut);
  CHECK(latch.workThread != std::this_thread::get_id());
  CHECK_FALSE(editor.checkError());
  CHECK(on.steps() == std::vector<std::string>{"name:vestibule", "locate:cochlea"});
  const lessons::Step& added = editor.draft().lessons[0].steps.back();
  CHECK(added.question.id == "async_quiz.lesson_1.q2");
  REQUIRE(added.scene.has_value());
  CHECK(added.scene->structure == "vestibule");
  CHECK(added.scene->presetId == "async_quiz.lesson_1.show_2");
  CHECK(editor.draft().title == "Renamed while checking");
  const auto checked = test::eventsOf(on.events, "course_question_checked");
  REQUIRE(checked.size() == 1);
  CHECK(checked[0]["added"] == true);

  // A view the check refuses: nothing is added, and the reason is the synchronous check's text.
  latch.released = false;
  latch.answerable = false;
  REQUIRE(editor.addQuestion(EditorOnPhantom::locate("stapes"), EditorOnPhantom::scene()));
  REQUIRE(editor.checking());
  latch.release();
  on.pollUntilChecked();
  REQUIRE(editor.checkError());
  CHECK(editor.checkError()->message == "question not added: the cochlea is not drawn in its view (test)");
  CHECK(on.steps() == std::vector<std::string>{"name:vestibule", "locate:cochlea"});
}

// The question belongs to the draft it was asked in: a new course started while it is checked drops
// it (the check is cancelled), and closing the editor while a check waits cancels the work and
// joins it at once.
TEST_CASE("CourseEditor_LocateCheckOutlivedByItsDraftOrEditor_IsDroppedAndJoinedCleanly") {
  LatchedCheck latch;
  {
    EditorOnPhantom on(latch.check());
    REQUIRE(on.editor->addQuestion(EditorOnPhantom::locate("cochlea"), EditorOnPhantom::scene()));
    REQUIRE(on.editor->newCourse("other_quiz", "", "phantom"));
    on.pollUntilChecked();
    CHECK(latch.sawCancel);
    REQUIRE(on.editor->checkError());
    CHECK((on.editor->checkError()->kind == ErrorKind::Cancelled));
    CHECK(on.editor->draft().id == "other_quiz");
    CHECK(on.editor->draft().lessons[0].steps.empty());
  }
  latch.sawCancel = false;
  EditorOnPhantom on(latch.check());
  REQUIRE(on.editor->addQuestion(EditorOnPhantom::locate("cochlea"), EditorOnPhantom::scene()));
  REQUIRE(on.editor->checking());
  const auto closing = std::chrono::steady_clock::now();
  on.editor.reset();
  CHECK(msSince(closing) < 1000);
  CHECK(latch.sawCancel);
  CHECK_FALSE(latch.timedOut);
}

// In the desktop the real view check runs on the editor's worker while the frames go on (the
// panels are drawn while it runs), the scripted action waits for its result, and the question is
// added as before.
TEST_CASE("CourseEditor_LocateQuestionInTheDesktop_IsCheckedWhileFramesGoOn") {
  test::TempDir author("at-author");
  int framesWhileChecking = 0;
  test::HeadlessOptions options = on(author / "a.db");
  options.drawPanels = [&](app::DesktopModel& model) { framesWhileChecking += model.courseEditor().checking(); };
  const json script = {{"actions", json::array({
      {{"do", "course_new"}, {"id", "frames_quiz"}},
      {{"do", "select"}, {"structure", "vestibule"}},
      {{"do", "view"}, {"value", "anterior"}},
      {{"do", "course_question"}, {"scene", true},
       {"question", {{"kind", "locate"}, {"prompt", "Click the cochlea."}, {"target", "cochlea"}}}},
      {{"do", "course_show"}, {"title", "After"}, {"text", "added once the check ended"}},
  })}};
  auto run = test::runHeadless(script, options);
  CAPTURE(run.messages);
  REQUIRE(run.exitCode == 0);
  CHECK(framesWhileChecking >= 1);
  const auto checked = test::eventsOf(run, "course_question_checked");
  REQUIRE(checked.size() == 1);
  CHECK(checked[0]["added"] == true);
  MESSAGE("the check took " << checked[0]["ms"].get<double>() << " ms over " << framesWhileChecking << " frames");
  CHECK(stepKinds(lastEdit(run)) == std::vector<std::string>{"locate:cochlea", "show:vestibule"});
}
