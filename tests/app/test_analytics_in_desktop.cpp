// The desktop's Class analytics window (instructors) as the UI script drives it: a class recorded
// in a real SQLite file on the shipped course (answers, attempts and FSRS states through the
// learning session's repositories), read back by the window's controller through the session —
// each structure's error rate, the items most missed, each student's progress — and compared with
// figures counted here from the answers as they were recorded. A scripted run under Xvfb shows
// the window at the default window size.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include "headless_desktop.h"
#include "learning_session.h"
#include "lessons/scheduling.h"
#include "volume/png_image.h"

using namespace at;
using json = nlohmann::json;

namespace {

constexpr const char* kCourse = "temporal_bone";

// What the test remembers of the class it records.
struct RecordedClass {
  std::map<std::string, std::pair<int, int>> byStructure, byQuestion;  // answers, wrong
  std::map<std::string, std::pair<int, int>> byStructureGroupB;
  std::map<std::string, int> lessonsFinished;  // per student name
  std::map<std::string, std::string> groupOf;
  int answers = 0;
};

// Twelve students (groups A and B) who work through the first lessons, each question answered
// right with a chance that grows with the student's skill, some stopping part-way.
RecordedClass recordClass(const std::filesystem::path& db, std::uint64_t seed) {
  RecordedClass rec;
  auto session = app::LearningSession::open(db.string());
  REQUIRE_MESSAGE(session, (session ? "" : session.error().message));
  auto courses = (*session)->curriculum().courses();
  REQUIRE(courses);
  const auto course = std::find_if(courses->begin(), courses->end(), [](const lessons::Course& c) { return c.id == kCourse; });
  REQUIRE(course != courses->end());
  lessons::ProgressRepository& progress = (*session)->progress();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const lessons::Fsrs fsrs;
  lessons::UnixSeconds clock = 1'760'000'000;
  for (int s = 0; s < 12; ++s) {
    const std::string name = "learner" + std::to_string(10 + s), group = s % 3 == 0 ? "B" : "A";
    auto user = (*session)->user(name, app::LearningSession::NewUser::Create, group);
    REQUIRE(user);
    rec.groupOf[name] = group;
    rec.lessonsFinished[name] = 0;
    const double skill = u(rng);
    std::map<std::string, lessons::StructureProgress> memory;
    for (const lessons::Lesson& lesson : course->lessons) {
      // Every student finishes the first lesson (6 questions: at least 72 answers in the class, so
      // the checks below always have data); later lessons are left or quit at random.
      const bool first = &lesson == &course->lessons.front();
      if (!first && u(rng) < 0.2) break;
      auto attempt = progress.startAttempt(user->id, lesson.id, lessons::LessonMode::Guided, clock);
      REQUIRE(attempt);
      double total = 0;
      int asked = 0;
      bool quit = false;
      for (std::size_t i = 0; i < lesson.steps.size(); ++i) {
        const lessons::Step& step = lesson.steps[i];
        if (step.kind != lessons::StepKind::Question) continue;
        if (!first && u(rng) < 0.05) {
          quit = true;
          break;
        }
        const bool correct = u(rng) < 0.25 + 0.7 * skill;
        clock += 40;
        lessons::AnswerRecord r;
        r.response.questionId = step.question.id;
        r.response.structureId = step.question.target;
        r.response.answer.text = "x";
        r.response.correct = correct;
        r.response.score = correct ? 1 : 0;
        r.response.latencyMs = 5000;
        r.response.answeredAt = clock;
        r.response.attemptId = attempt->id;
        r.response.stepIndex = int(i);
        const std::string& target = step.question.target;
        const lessons::StructureProgress before =
            memory.count(target) ? memory[target]
                                 : lessons::StructureProgress{.userId = user->id, .structureId = target, .memory = {}};
        r.update.rating = lessons::ratingFor(correct, r.response.score, step.question.kind, r.response.latencyMs);
        r.update.memoryBefore = before.memory;
        r.update.progress = lessons::scheduleAnswer(before, r.update.rating, correct, clock, fsrs);
        memory[target] = r.update.progress;
        REQUIRE(progress.recordAnswer(r));
        const int wrong = correct ? 0 : 1;
        for (auto* table : {&rec.byStructure, &rec.byQuestion}) {
          auto& [n, w] = (*table)[table == &rec.byStructure ? target : step.question.id];
          ++n;
          w += wrong;
        }
        if (group == "B") {
          auto& [n, w] = rec.byStructureGroupB[target];
          ++n;
          w += wrong;
        }
        ++rec.answers;
        total += r.response.score;
        ++asked;
      }
      if (quit) break;
      REQUIRE(progress.finishAttempt(attempt->id, clock + 5, asked ? total / asked : 1));
      ++rec.lessonsFinished[name];
    }
    clock += 3600;
  }
  return rec;
}

std::vector<json> analyticsEvents(const test::HeadlessRun& run) { return test::eventsOf(run, "analytics"); }

// The users stored in the class's database, by name.
std::set<std::string> storedUsers(const std::filesystem::path& db) {
  auto session = app::LearningSession::open(db.string());
  REQUIRE_MESSAGE(session, (session ? "" : session.error().message));
  auto users = (*session)->users().users();
  REQUIRE(users);
  std::set<std::string> names;
  for (const lessons::User& u : *users) names.insert(u.name);
  return names;
}

}  // namespace

TEST_CASE("Class analytics in the desktop: error rates, most missed items and each student's progress match the class") {
  test::TempDir dir("desktop_analytics");
  const auto db = dir / "class.db";
  const RecordedClass rec = recordClass(db, test::freshSeed("DesktopAnalytics_Class"));
  REQUIRE(rec.answers > 50);

  test::HeadlessOptions options;
  options.db = db;
  options.user = "instructor";  // not a student of the class: made only once it starts a lesson
  std::optional<lessons::ClassAnalytics> shown;
  std::vector<lessons::QuestionStats> missed;
  options.drawPanels = [&](app::DesktopModel& model) {
    app::AnalyticsController& a = model.analytics();
    if (a.loaded() && !a.group()) {
      shown = a.analytics();
      missed = a.mostMissed(10);
    }
  };
  const auto before = storedUsers(db);
  REQUIRE(before.size() == 12);
  // The instructor looks at the lesson list and the review queue first (as the Lessons panel does
  // in every frame): looking makes no student.
  const auto run = test::runHeadless(
      {{"actions", {{{"do", "lessons"}, {"course", kCourse}}, {{"do", "review"}},
                    {{"do", "analytics"}, {"course", kCourse}}, {{"do", "wait"}, {"ms", 50}},
                    {{"do", "analytics"}, {"course", kCourse}, {"group", "B"}}, {{"do", "analytics"}, {"close", true}}}}},
      options);
  INFO(run.messages);
  REQUIRE(run.exitCode == 0);
  const auto events = analyticsEvents(run);
  REQUIRE(events.size() == 2);
  REQUIRE(shown);

  // The whole class: the twelve learners, every recorded answer.
  const json& all = events[0];
  CHECK(all["class_size"] == 12);
  CHECK(all["answers"] == rec.answers);
  CHECK(shown->answers == rec.answers);
  // Per structure: the share of its answers that were wrong.
  REQUIRE(all["structures"].size() == rec.byStructure.size());
  for (const json& s : all["structures"]) {
    const auto& [n, wrong] = rec.byStructure.at(s["id"].get<std::string>());
    CAPTURE(s.dump());
    CHECK(s["answers"] == n);
    CHECK(s["error_rate"].get<double>() == doctest::Approx(double(wrong) / n));
  }
  for (std::size_t i = 1; i < shown->structures.size(); ++i)  // hardest first
    CHECK(shown->structures[i - 1].correctShare <= shown->structures[i].correctShare);
  // The items most missed: by wrong answers, then the share of wrong answers, then id.
  std::vector<std::tuple<int, double, std::string>> expected;
  for (const auto& [id, counts] : rec.byQuestion)
    if (counts.second > 0) expected.emplace_back(-counts.second, double(counts.first - counts.second) / counts.first, id);
  std::sort(expected.begin(), expected.end());
  REQUIRE(!expected.empty());
  REQUIRE(all["most_missed"].size() == std::min<std::size_t>(10, expected.size()));
  REQUIRE(missed.size() == all["most_missed"].size());
  for (std::size_t i = 0; i < missed.size(); ++i) {
    CHECK(all["most_missed"][i]["question"] == std::get<2>(expected[i]));
    CHECK(all["most_missed"][i]["missed"] == -std::get<0>(expected[i]));
    CHECK(missed[i].questionId == std::get<2>(expected[i]));
  }
  // Per student: lessons finished; predicted recall for those who answered something.
  REQUIRE(all["students"].size() == 12);
  for (const json& s : all["students"]) {
    const std::string name = s["name"];
    CAPTURE(name);
    CHECK(s["lessons_finished"] == rec.lessonsFinished.at(name));
    if (s["taught"].get<int>() > 0) {
      CHECK(s["mean_recall"].get<double>() > 0);
      CHECK(s["mean_recall"].get<double>() <= 1);
    }
  }

  // Group B only: its students, and only their answers count.
  const json& b = events[1];
  CHECK(b["group"] == "B");
  CHECK(b["class_size"] == std::count_if(rec.groupOf.begin(), rec.groupOf.end(), [](const auto& g) { return g.second == "B"; }));
  for (const json& s : b["structures"]) {
    const auto& [n, wrong] = rec.byStructureGroupB.at(s["id"].get<std::string>());
    CHECK(s["answers"] == n);
    CHECK(s["error_rate"].get<double>() == doctest::Approx(double(wrong) / n));
  }

  CHECK(storedUsers(db) == before);  // viewing created no user and no progress

  // Wrong input: an unknown course or group fails the script with a message naming it; the
  // groups there are are listed.
  const auto unknownCourse = test::runHeadless({{"actions", {{{"do", "analytics"}, {"course", "nope"}}}}}, options);
  CHECK(unknownCourse.exitCode == 2);
  CHECK(unknownCourse.messages.find("nope") != std::string::npos);
  const auto unknownGroup =
      test::runHeadless({{"actions", {{{"do", "analytics"}, {"course", kCourse}, {"group", "Z"}}}}}, options);
  CHECK(unknownGroup.exitCode == 2);
  CHECK(unknownGroup.messages.find("group 'Z' (groups: A, B)") != std::string::npos);
  const auto unknownTab =
      test::runHeadless({{"actions", {{{"do", "analytics"}, {"course", kCourse}, {"tab", "charts"}}}}}, options);
  CHECK(unknownTab.exitCode == 2);
  CHECK(unknownTab.messages.find("tab must be") != std::string::npos);
}

TEST_CASE("the Class analytics window under Xvfb at 1280x720: tables of the class, nothing clipped off the window") {
  if (!test::requireXvfb()) return;
  test::TempDir dir("desktop_analytics_xvfb");
  const auto db = dir / "class.db";
  recordClass(db, test::freshSeed("DesktopAnalytics_Screenshot"));
  const auto shot = dir / "analytics.png";
  json actions = {{{"do", "analytics"}, {"course", kCourse}}, {{"do", "wait"}, {"ms", 300}}, {{"do", "screenshot"}, {"path", shot.string()}}};
  for (const char* tab : {"missed", "students", "lessons"}) {
    actions.push_back({{"do", "analytics"}, {"course", kCourse}, {"tab", tab}});
    actions.push_back({{"do", "wait"}, {"ms", 300}});
    actions.push_back({{"do", "screenshot"}, {"path", (dir / (std::string("analytics_") + tab + ".png")).string()}});
  }
  const auto run = test::runLaptopScript(dir, actions, db, "instructor");
  INFO(run.err);
  REQUIRE(run.exitCode == 0);
  CHECK(test::eventsOf(run.events, "screenshot").size() == 4);
  // The window's Lessons panel drew the instructor's (empty) lesson list in every frame: the class
  // is still its twelve students, in the window and in the database.
  const auto shown = test::eventsOf(run.events, "analytics");
  REQUIRE(shown.size() == 4);
  for (const json& e : shown) CHECK(e["class_size"] == 12);
  CHECK(storedUsers(db).size() == 12);
  CHECK_FALSE(storedUsers(db).count("instructor"));
  auto image = readPng(shot.string());
  REQUIRE_MESSAGE(image, (image ? "" : image.error().message));
  CHECK(image->width == test::kLaptopWidth);
  CHECK(image->height == test::kLaptopHeight);
  // The window's bars: the error-rate bars are drawn in their red over the view's right part.
  int red = 0;
  for (int y = 0; y < image->height; ++y)
    for (int x = image->width / 3; x < image->width; ++x) {
      const auto* p = &image->rgb[(std::size_t(y) * std::size_t(image->width) + std::size_t(x)) * 3];
      red += p[0] > 190 && p[1] > 70 && p[1] < 110 && p[2] > 60 && p[2] < 100 ? 1 : 0;
    }
  CHECK(red > 2000);
  // For a person to look at: AT_KEEP_SCREENSHOTS=DIR keeps a copy of each tab.
  if (const char* keep = std::getenv("AT_KEEP_SCREENSHOTS"))
    for (const char* name : {"analytics", "analytics_missed", "analytics_students", "analytics_lessons"})
      std::filesystem::copy_file(dir / (std::string(name) + ".png"), std::filesystem::path(keep) / (std::string("desktop_") + name + ".png"),
                                 std::filesystem::copy_options::overwrite_existing);
}
