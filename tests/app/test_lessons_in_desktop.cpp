// The desktop lesson runner as a user meets it, without a window (its logic is at_app_core's): UI
// scripts that start lessons through the LessonEngine, answer questions of several kinds (locate by
// a click in the 3-D view, picked on the CPU as in the app), and leave their answers in the
// database where `anatomy-tutor progress` finds them.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/sql_repositories.h"
#include "headless_desktop.h"
#include "lessons/course_json.h"
#include "skull_scan.h"
#include "test_support.h"

namespace fs = std::filesystem;
using at::test::TempDir;
using json = nlohmann::json;

namespace {

using Run = at::test::HeadlessRun;
using at::test::eventsOf;

// Runs `script` on the 128³ phantom as in an 800×600 window, with lesson progress in `db` under the
// user `user`.
Run runLessonScript(const TempDir&, const json& script, const fs::path& db, const std::string& user) {
  at::test::HeadlessOptions options;
  options.height = 600;
  options.renderScale = 0.3;
  options.db = db;
  options.user = user;
  return at::test::runHeadless(script, options);
}

json next(int times) {
  json actions = json::array();
  for (int i = 0; i < times; ++i) actions.push_back({{"do", "lesson_next"}});
  return actions;
}

void append(json& list, const json& more) {
  for (const json& a : more) list.push_back(a);
}

}  // namespace

TEST_CASE("a desktop lesson grades clicks, choices and names, records them, resumes, and the terminal sees the same progress") {
  TempDir dir("desktop-lessons");
  const fs::path db = dir / "tutor.db";
  // inner_ear: four show steps, then locate the cochlea, identify the vestibule, name the lateral
  // canal. The cochlea is clicked (from above in the WDT view, where nothing lies in front of it;
  // the view settled first, since picking classifies with the shown field), the vestibule
  // chosen (right), the canal misnamed (wrong).
  json actions = {{{"do", "lessons"}, {"course", "temporal_bone"}},
                  {{"do", "lesson"}, {"course", "temporal_bone"}, {"lesson", "inner_ear"}}};
  append(actions, next(4));
  append(actions, {{{"do", "mode"}, {"value", "wdt"}},  // the last show step left the bare preset on
                   {{"do", "view"}, {"value", "superior"}},
                   {{"do", "wait_field"}},
                   {{"do", "click_structure"}, {"structure", "cochlea"}},
                   {{"do", "lesson_next"}},
                   {{"do", "answer"}, {"value", "vestibule"}},
                   {{"do", "lesson_next"}},
                   {{"do", "answer"}, {"value", "cochlea"}}});
  const Run r = runLessonScript(dir, {{"actions", actions}}, db, "tester");
  INFO(r.messages);
  REQUIRE(r.exitCode == 0);

  // Before any answer: the first lesson open, the others locked behind their prerequisites.
  const auto lists = eventsOf(r, "lessons");
  REQUIRE(lists.size() == 1);
  const json& rows = lists[0].at("lessons");
  REQUIRE(rows.size() == 4);
  CHECK(rows[0].value("id", "") == "inner_ear");
  CHECK_FALSE(rows[0].value("locked", true));
  CHECK(rows[1].value("locked", false));
  CHECK(rows[1].at("missing") == json{"The inner ear"});
  CHECK(rows[3].at("missing").size() == 2);

  const auto started = eventsOf(r, "lesson_started");
  REQUIRE(started.size() == 1);
  CHECK(started[0].value("user", "") == "tester");
  CHECK_FALSE(started[0].value("resumed", true));
  const auto steps = eventsOf(r, "lesson_step");
  REQUIRE(steps.size() == 7);
  CHECK(steps[0].value("kind", "") == "show");
  CHECK(steps[4].value("question_kind", "") == "locate");
  CHECK(steps[5].value("question_kind", "") == "identify");
  CHECK(steps[6].value("question_kind", "") == "name");

  const auto graded = eventsOf(r, "graded");
  REQUIRE(graded.size() == 3);
  CHECK(graded[0].value("question", "") == "inner_ear.locate_cochlea");
  CHECK(graded[0].value("clicked", "") == "cochlea");
  CHECK(graded[0].value("correct", false));
  CHECK(graded[1].value("question", "") == "inner_ear.identify_vestibule");
  CHECK(graded[1].value("correct", false));
  CHECK(graded[1].value("score", 0.0) == doctest::Approx(1.0));
  CHECK(graded[2].value("question", "") == "inner_ear.name_lateral_canal");
  CHECK_FALSE(graded[2].value("correct", true));
  CHECK(graded[2].value("score", 1.0) == doctest::Approx(0.0));
  CHECK_FALSE(graded[2].value("feedback", "").empty());
  for (const json& g : graded) CHECK_FALSE(g.value("review", true));

  // The answers are in the database: the terminal's progress report counts them per structure.
  const auto progress = at::test::runApp("progress --user tester --db '" + db.string() + "'");
  INFO(progress.out << progress.err);
  REQUIRE(progress.exitCode == 0);
  CHECK(progress.out.find("3 answers, 2 correct") != std::string::npos);
  CHECK(progress.out.find("in progress") != std::string::npos);
  std::istringstream lines(progress.out);
  int structureLines = 0;
  for (std::string line; std::getline(lines, line);) {
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string x; words >> x;) w.push_back(x);
    // "  Cochlea   1   1   100%  in 8 days": name, answered, correct, recall now, next review.
    const auto has = [&](const std::string& name) { return line.find("  " + name + " ") == 0; };
    if (has("Cochlea") || has("Vestibule")) {
      REQUIRE(w.size() >= 4);
      ++structureLines;
      CHECK(w[1] == "1");  // answered
      CHECK(w[2] == "1");  // correct
      // Just answered right: in Review (fast, Easy) recalled for sure, or still in its learning steps.
      CHECK((w[3] == "100%" || w[3] == "learning"));
    }
  }
  CHECK(structureLines == 2);

  // Run again: the open attempt resumes after the last answered question (locate the superior
  // canal); a click on another structure (what lies over the cochlea from above) is graded wrong; the two relation questions are
  // answered, and the lesson finishes with the mean score of its six answers.
  json more = {{{"do", "lesson"}, {"lesson", "inner_ear"}},
               {{"do", "mode"}, {"value", "wdt"}},
               {{"do", "view"}, {"value", "superior"}},
               {{"do", "wait_field"}},
               {{"do", "click_structure"}, {"structure", "cochlea"}},
               {{"do", "lesson_next"}},
               {{"do", "answer"}, {"value", 0}},
               {{"do", "lesson_next"}},
               {{"do", "answer"}, {"value", 0}},
               {{"do", "lesson_next"}},
               {{"do", "lessons"}},
               {{"do", "lesson_user"}, {"name", "someone_else"}},
               {{"do", "lessons"}}};
  const Run again = runLessonScript(dir, {{"actions", more}}, db, "tester");
  INFO(again.messages);
  REQUIRE(again.exitCode == 0);
  const auto resumed = eventsOf(again, "lesson_started");
  REQUIRE(resumed.size() == 1);
  CHECK(resumed[0].value("resumed", false));
  const auto resumedSteps = eventsOf(again, "lesson_step");
  REQUIRE(resumedSteps.size() == 3);
  CHECK(resumedSteps[0].value("position", 0) == 8);
  CHECK(resumedSteps[0].value("question", "") == "inner_ear.locate_superior_canal");
  CHECK(resumedSteps[1].value("question_kind", "") == "relation");
  const auto moreGraded = eventsOf(again, "graded");
  REQUIRE(moreGraded.size() == 3);
  const std::string missedOn = moreGraded[0].value("clicked", "");
  CHECK_FALSE(missedOn.empty());
  CHECK(missedOn != "superior_semicircular_canal");
  CHECK_FALSE(moreGraded[0].value("correct", true));
  // The question accepts clicks within 0.4 mm of the canal: the miss is graded with the clicked
  // point's weighted distance from it, which the stored answer keeps.
  const json& missed = moreGraded[0].at("answer");
  REQUIRE(missed.contains("distance_mm"));
  CHECK(missed.at("distance_mm").get<double>() > 0.4);
  double total = 0;
  for (const json& g : graded) total += g.value("score", 0.0);
  for (const json& g : moreGraded) total += g.value("score", 0.0);
  const auto finished = eventsOf(again, "lesson_finished");
  REQUIRE(finished.size() == 1);
  CHECK(finished[0].value("score", -1.0) == doctest::Approx(total / 6));
  // Finished: the lessons that needed only it are open now, the last one still needs two.
  const auto after = eventsOf(again, "lessons");
  REQUIRE(after.size() == 2);
  const json& rowsAfter = after[0].at("lessons");
  CHECK(rowsAfter[0].value("best_score", -1.0) == doctest::Approx(total / 6));
  CHECK_FALSE(rowsAfter[1].value("locked", true));
  CHECK_FALSE(rowsAfter[2].value("locked", true));
  CHECK(rowsAfter[3].value("locked", false));
  // Progress is per user: another user starts from nothing.
  const json& other = after[1].at("lessons");
  CHECK(other[0].value("attempts", -1) == 0);
  CHECK(other[1].value("locked", false));
  REQUIRE(eventsOf(again, "lesson_user").size() == 1);
  CHECK(eventsOf(again, "lesson_user")[0].value("user", "") == "someone_else");
  const auto report = at::test::runApp("progress --user tester --db '" + db.string() + "'");
  CHECK(report.out.find("finished, best score") != std::string::npos);
}

TEST_CASE("a lesson whose prerequisites are unfinished cannot be started from a script, and says which they are") {
  TempDir dir("desktop-lessons-locked");
  const fs::path db = dir / "tutor.db";
  // The open first lesson starts (in quiz-only mode: its questions alone); the locked one refuses.
  const json actions = {{{"do", "lesson"}, {"lesson", "inner_ear"}, {"mode", "quiz_only"}},
                        {{"do", "lesson"}, {"lesson", "mastoidectomy_landmarks"}}};
  const Run r = runLessonScript(dir, {{"actions", actions}}, db, "newcomer");
  INFO(r.messages);
  CHECK(r.exitCode == 2);
  const auto started = eventsOf(r, "lesson_started");
  REQUIRE(started.size() == 1);
  CHECK(started[0].value("mode", "") == "quiz_only");
  const auto steps = eventsOf(r, "lesson_step");
  REQUIRE(steps.size() == 1);
  CHECK(steps[0].value("kind", "") == "question");
  CHECK(steps[0].value("count", 0) == 6);
  const auto refused = eventsOf(r, "lesson_refused");
  REQUIRE(refused.size() == 1);
  const std::string message = refused[0].value("message", "");
  CHECK(message.find("facial_nerve") != std::string::npos);
  CHECK(message.find("middle_ear") != std::string::npos);
  CHECK(r.messages.find("needs") != std::string::npos);
}

namespace {

// `user` has been taught the vestibule in "The inner ear" (an attempt, one answer) and it is due
// now: the state a student is in a few days after the lesson. The database is created and the
// default course seeded first (by `anatomy-tutor courses`).
void vestibuleTaughtAndDue(const fs::path& db, const std::string& user) {
  REQUIRE(at::test::runApp("courses --db '" + db.string() + "'").exitCode == 0);
  auto database = at::db::Database::open(db.string());
  REQUIRE(database);
  auto teach = database->prepare("INSERT INTO users (name) VALUES (?1)");
  REQUIRE(teach);
  teach->bind(1, user);
  REQUIRE(teach->run());
  auto attempt = database->prepare(
      "INSERT INTO attempts (user_id, lesson_id, mode, started_at) SELECT id, 'inner_ear', 'guided',"
      " CAST(strftime('%s', 'now') AS INTEGER) - 5 * 86400 FROM users WHERE name = ?1");
  REQUIRE(attempt);
  attempt->bind(1, user);
  REQUIRE(attempt->run());
  auto memory = database->prepare(
      "INSERT INTO memory_states (user_id, structure, phase, stability, difficulty, due_at, last_review_at, reviews,"
      " answered, correct) SELECT id, 'vestibule', 'review', 3.2, 2.1, CAST(strftime('%s', 'now') AS INTEGER) - 60,"
      " CAST(strftime('%s', 'now') AS INTEGER) - 4 * 86400, 2, 2, 2 FROM users WHERE name = ?1");
  REQUIRE(memory);
  memory->bind(1, user);
  REQUIRE(memory->run());
}

}  // namespace

TEST_CASE("the review button asks about a taught structure that is due, and grades its answer without a lesson running") {
  TempDir dir("desktop-lessons-review");
  const fs::path db = dir / "tutor.db";
  // Nothing taught yet: nothing is due and nothing is asked (no questions from unstarted lessons).
  const Run r = runLessonScript(dir, {{"actions", {{{"do", "review"}}}}}, db, "newcomer");
  INFO(r.messages);
  REQUIRE(r.exitCode == 0);
  const auto queue = eventsOf(r, "review_queue");
  REQUIRE(queue.size() == 1);
  CHECK(queue[0].at("due").empty());
  const auto asked = eventsOf(r, "review_question");
  REQUIRE(asked.size() == 1);
  CHECK(asked[0].at("question").is_null());

  // Taught and due: the queue lists it and the review asks about it (its identify question, the
  // one whose difficulty suits a new student best); answered right, it leaves the queue.
  vestibuleTaughtAndDue(db, "reviewer");
  const Run answered = runLessonScript(
      dir, {{"actions", {{{"do", "review"}}, {{"do", "answer"}, {"value", "vestibule"}}, {{"do", "review"}}}}}, db,
      "reviewer");
  INFO(answered.messages);
  REQUIRE(answered.exitCode == 0);
  const auto queues = eventsOf(answered, "review_queue");
  REQUIRE(queues.size() == 2);
  CHECK(queues[0].at("due") == json::array({"vestibule"}));
  CHECK(queues[0].at("names") == json::array({"Vestibule"}));  // named as the dataset names it, before any lesson ran
  CHECK(queues[1].at("due").empty());
  const auto again = eventsOf(answered, "review_question");
  REQUIRE(again.size() == 2);
  CHECK(again[0].value("question", "") == "inner_ear.identify_vestibule");
  CHECK(again[0].value("course", "") == "temporal_bone");
  CHECK(again[1].at("question").is_null());
  const auto graded = eventsOf(answered, "graded");
  REQUIRE(graded.size() == 1);
  CHECK(graded[0].value("review", false));
  CHECK(graded[0].value("correct", false));
  CHECK(graded[0].value("recorded", false));
}

namespace {

std::vector<std::string> dueIn(const json& queueEvent) {
  std::vector<std::string> due;
  for (const json& id : queueEvent.at("due")) due.push_back(id.get<std::string>());
  return due;
}

bool lists(const std::vector<std::string>& due, const std::string& structure) {
  return std::find(due.begin(), due.end(), structure) != due.end();
}

}  // namespace

TEST_CASE("a review answer is recorded: a wrong one puts its structure in the queue, a right one takes it out") {
  TempDir dir("desktop-lessons-review-queue");
  const fs::path db = dir / "tutor.db";
  vestibuleTaughtAndDue(db, "reviewer");
  const std::string question = "inner_ear.identify_vestibule", target = "vestibule";
  const json right = target;
  // The question and its choices (computed from the weighted distances: fixed for the dataset).
  const Run first = runLessonScript(dir, {{"actions", {{{"do", "review"}}}}}, db, "reviewer");
  INFO(first.messages);
  REQUIRE(first.exitCode == 0);
  const auto shown = eventsOf(first, "review_question");
  REQUIRE(shown.size() == 1);
  REQUIRE(shown[0].value("question", "") == question);
  json wrong;
  for (const json& c : shown[0].at("choices"))
    if (c != target) wrong = c;
  REQUIRE(wrong.is_string());

  // Answered wrong: recorded, a lapse: the structure relearns, due again in 10 minutes.
  const Run missed = runLessonScript(dir, {{"actions", {{{"do", "review"}}, {{"do", "answer"}, {"value", wrong}}}}},
                                     db, "reviewer");
  INFO(missed.messages);
  REQUIRE(missed.exitCode == 0);
  REQUIRE(eventsOf(missed, "review_question").size() == 1);
  REQUIRE(eventsOf(missed, "review_question")[0].value("question", "") == question);
  const auto missedGrade = eventsOf(missed, "graded");
  REQUIRE(missedGrade.size() == 1);
  CHECK_FALSE(missedGrade[0].value("correct", true));
  CHECK(missedGrade[0].value("recorded", false));
  {
    auto database = at::db::Database::open(db.string());
    REQUIRE(database);
    at::db::SqlUserRepository users(*database);
    at::db::SqlProgressRepository progress(*database);
    auto user = users.findUser("reviewer");
    REQUIRE(user);
    REQUIRE(user->has_value());
    auto stored = progress.reviewResponses((*user)->id);
    REQUIRE(stored);
    REQUIRE(stored->size() == 1);
    CHECK((*stored)[0].questionId == question);
    CHECK((*stored)[0].structureId == target);
    CHECK_FALSE((*stored)[0].correct);
    CHECK((*stored)[0].render.mode == "wdt");
    auto p = progress.progress((*user)->id, target);
    REQUIRE(p);
    REQUIRE(p->has_value());
    CHECK(((*p)->memory.phase == at::lessons::MemoryPhase::Relearning));
    CHECK((*p)->memory.lapses == 1);
    CHECK((*p)->memory.due == (*stored)[0].answeredAt + 600);
    // Ten minutes pass: the structure is due again.
    REQUIRE(database->exec("UPDATE memory_states SET due_at = due_at - 600, last_review_at = last_review_at - 600"));
  }

  // In the queue now; answered right it leaves the queue at once, and nothing is left to review.
  const Run fixed = runLessonScript(
      dir, {{"actions", {{{"do", "review"}}, {{"do", "answer"}, {"value", right}}, {{"do", "review"}}}}}, db, "reviewer");
  INFO(fixed.messages);
  REQUIRE(fixed.exitCode == 0);
  const auto queues = eventsOf(fixed, "review_queue");
  REQUIRE(queues.size() == 2);
  CHECK(dueIn(queues[0]) == std::vector<std::string>{target});
  CHECK_FALSE(lists(dueIn(queues[1]), target));
  const auto reasked = eventsOf(fixed, "review_question");
  REQUIRE(reasked.size() == 2);
  REQUIRE(reasked[0].value("target", "") == target);
  CHECK(reasked[1].at("question").is_null());
  const auto fixedGrade = eventsOf(fixed, "graded");
  REQUIRE(fixedGrade.size() == 1);
  CHECK(fixedGrade[0].value("correct", false));
  CHECK(fixedGrade[0].value("review", false));
  CHECK(fixedGrade[0].value("recorded", false));

  // The database holds both review answers, and the terminal's report counts them.
  {
    auto database = at::db::Database::open(db.string());
    REQUIRE(database);
    at::db::SqlUserRepository users(*database);
    at::db::SqlProgressRepository progress(*database);
    const std::int64_t userId = (**users.findUser("reviewer")).id;
    auto stored = progress.reviewResponses(userId);
    REQUIRE(stored);
    REQUIRE(stored->size() == 2);
    CHECK((*stored)[1].correct);
    CHECK((*stored)[1].questionId == reasked[0].value("question", ""));
    auto p = progress.progress(userId, target);
    REQUIRE(p->has_value());
    CHECK((*p)->memory.due >= (*stored)[1].answeredAt + 86400);  // relearned: back in Review, days away
    CHECK((*p)->correct == 3);
  }
  const auto report = at::test::runApp("progress --user reviewer --db '" + db.string() + "'");
  INFO(report.out << report.err);
  REQUIRE(report.exitCode == 0);
  CHECK(report.out.find("(2 in review, 1 correct)") != std::string::npos);
  CHECK(report.out.find("Due for review now: nothing") != std::string::npos);
}

namespace {

// For each locate question of the course in data/courses/`file`, on `dataset`: a student whose
// lesson prerequisites are finished and who answered the lesson's earlier questions (as the
// database keeps them) resumes the lesson, steps to the question, lets the view settle and clicks
// where the target appears. The step must show a view in which that click picks the target (not a
// view left over from the step before). Returns how many questions were clicked.
int clickEveryLocateQuestion(const std::string& file, const std::string& dataset) {
  auto course = at::lessons::loadCourseJson(at::test::sourceDir() / "data" / "courses" / file);
  REQUIRE(course);
  int checked = 0;
  for (const auto& lesson : course->lessons)
    for (std::size_t stepIndex = 0; stepIndex < lesson.steps.size(); ++stepIndex) {
      const auto& step = lesson.steps[stepIndex];
      if (step.kind != at::lessons::StepKind::Question || step.question.kind != at::quiz::QuestionKind::Locate) continue;
      const std::string qid = step.question.id;
      CAPTURE(qid);
      TempDir dir("desktop-locate");
      const fs::path db = dir / "tutor.db";
      int shows = 0;  // show steps between the resumed position and the question
      {
        auto database = at::db::Database::open(db.string());
        REQUIRE(database);
        REQUIRE(database->exec("INSERT INTO users (id, name) VALUES (1, 'clicker')"));
        int attempt = 1;
        for (const std::string& pre : lesson.prerequisites) {
          auto done = database->prepare("INSERT INTO attempts (id, user_id, lesson_id, mode, started_at, finished_at, score)"
                                        " VALUES (?1, 1, ?2, 'guided', 100, 200, 1)");
          REQUIRE(done);
          done->bind(1, attempt++).bind(2, pre);
          REQUIRE(done->run());
        }
        auto open = database->prepare("INSERT INTO attempts (id, user_id, lesson_id, mode, started_at) VALUES (?1, 1, ?2, 'guided', 300)");
        REQUIRE(open);
        open->bind(1, attempt).bind(2, lesson.id);
        REQUIRE(open->run());
        for (std::size_t i = 0; i < stepIndex; ++i) {
          const auto& before = lesson.steps[i];
          if (before.kind != at::lessons::StepKind::Question) {
            ++shows;
            continue;
          }
          shows = 0;
          auto answered = database->prepare(
              "INSERT INTO responses (attempt_id, step_index, question_id, structure, answer, correct, score, latency_ms,"
              " answered_at) VALUES (?1, ?2, ?3, ?4, '{\"pick\": \"\"}', 0, 0, 0, 310)");
          REQUIRE(answered);
          answered->bind(1, attempt).bind(2, int(i)).bind(3, before.question.id).bind(4, before.question.target);
          REQUIRE(answered->run());
        }
      }
      json actions = {{{"do", "lesson"}, {"course", course->id}, {"lesson", lesson.id}}};
      append(actions, next(shows));
      append(actions, {{{"do", "wait_field"}}, {{"do", "click_structure"}, {"structure", step.question.target}}});
      at::test::HeadlessOptions options;
      options.dataset = dataset;
      options.course = course->id;
      options.height = 600;
      options.renderScale = 0.3;
      options.db = db;
      options.user = "clicker";
      const Run r = at::test::runHeadless({{"actions", actions}}, options);
      INFO(r.messages);
      REQUIRE(r.exitCode == 0);
      const auto steps = eventsOf(r, "lesson_step");
      REQUIRE_FALSE(steps.empty());
      CHECK(steps.back().value("question", "") == qid);
      const auto clicked = eventsOf(r, "click_structure");
      REQUIRE(clicked.size() == 1);
      CHECK(clicked[0].value("visible", false));
      const auto graded = eventsOf(r, "graded");
      REQUIRE(graded.size() == 1);
      CHECK(graded[0].value("question", "") == qid);
      CHECK_MESSAGE(graded[0].value("correct", false), "clicked " << graded[0].value("clicked", std::string("?")));
      ++checked;
    }
  return checked;
}

}  // namespace

TEST_CASE("every locate question of the shipped courses shows its region, and a click on the target's centre is right the first time") {
  CHECK(clickEveryLocateQuestion("temporal_bone.json", "phantom:128") == 6);
}

TEST_CASE("every locate question of the skull course shows its region, and a click on the target's centre is right the first time") {
  // The skull CT with its labels grown from the kept seeds; among them the ethmoid cells, asked on
  // a coronal cut, whose two labyrinths lie on either side of the nasal cavity's cleft.
  const auto& cache = at::test::grownSkullCache();
  if (!cache) return;
  at::test::SkullCacheScope scope(*cache);
  CHECK(clickEveryLocateQuestion("skull.json", "skull") == 4);
}
