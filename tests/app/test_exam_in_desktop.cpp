// The desktop's practical exam as a student meets it, without a window (at_app_core's logic, driven
// by UI scripts): the course's exam behind its prerequisite lessons, items drawn once and resumed,
// locate items answered by a click in the 3-D view (turned so that the target can be clicked) or on
// a CT slice, identify and name items in the panel — and no grade anywhere until the exam is handed
// in; then every item's result and the score, in the events and in the database.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "desktop_exam_fixtures.h"
#include "headless_desktop.h"
#include "test_support.h"

namespace fs = std::filesystem;
using at::test::TempDir;
using json = nlohmann::json;

namespace {

using Run = at::test::HeadlessRun;
using at::test::eventsOf;
using at::test::prepareStudent;
using at::test::StoredItem;
using at::test::storedItems;

constexpr const char* kExam = "temporal_bone.practical";

Run runExamScript(const json& actions, const fs::path& db) { return at::test::runPanelScript(actions, db, "examinee"); }

// Any grade in an event: what an exam must not show before it is handed in.
bool showsGrade(const json& e) {
  return e.value("event", "") == "graded" || e.contains("correct") || e.contains("feedback") || e.contains("score");
}

}  // namespace

TEST_CASE("a desktop exam: names and grades hidden until it is handed in, clicks in 3-D and on slices, results stored") {
  TempDir dir("desktop-exam");
  const fs::path db = dir / "tutor.db";
  {
    // Locked until the prerequisites are finished: the list says so and the start is refused.
    const Run r = runExamScript({{{"do", "lessons"}, {"course", "temporal_bone"}}, {{"do", "exams"}}}, db);
    INFO(r.messages);
    REQUIRE(r.exitCode == 0);
    const auto lists = eventsOf(r, "exams");
    REQUIRE(lists.size() == 1);
    REQUIRE(lists[0].at("exams").size() == 1);
    CHECK(lists[0]["exams"][0].value("id", "") == kExam);
    CHECK(lists[0]["exams"][0].value("locked", false));
    const Run refused = runExamScript({{{"do", "exam"}, {"exam", kExam}}}, db);
    CHECK(refused.exitCode == 2);
    CHECK(refused.messages.find("needs") != std::string::npos);
  }
  prepareStudent(db);

  // Start, look at the first item, leave: the items are drawn and stored, the clock runs on.
  const Run first = runExamScript({{{"do", "lessons"}, {"course", "temporal_bone"}}, {{"do", "exams"}},
                                   {{"do", "exam"}, {"exam", kExam}}, {{"do", "exam_leave"}}}, db);
  INFO(first.messages);
  REQUIRE(first.exitCode == 0);
  const auto lists = eventsOf(first, "exams");
  REQUIRE(lists.size() == 1);
  CHECK_FALSE(lists[0]["exams"][0].value("locked", true));
  REQUIRE(eventsOf(first, "exam_started").size() == 1);
  CHECK_FALSE(eventsOf(first, "exam_started")[0].value("resumed", true));
  const std::vector<StoredItem> items = storedItems(db);
  REQUIRE(items.size() == 12);
  CHECK(std::none_of(items.begin(), items.end(), [](const StoredItem& i) { return i.answered; }));

  // Resume and answer every item as a student who knows them all, except the first identify item,
  // answered with a wrong choice; then hand in.
  json actions = {{{"do", "exam"}, {"exam", kExam}}};
  int wrongPosition = -1, locate3d = 0, locateSlice = 0;
  for (const StoredItem& item : items) {
    actions.push_back({{"do", "exam_item"}, {"position", item.position}});
    if (item.kind == "locate" && item.locateView == "3d") {
      ++locate3d;
      actions.push_back({{"do", "wait_field"}});
      actions.push_back({{"do", "click_structure"}, {"structure", item.structure}});
    } else if (item.kind == "locate") {
      ++locateSlice;
      actions.push_back({{"do", "slice_click_structure"}, {"structure", item.structure}});
    } else if (item.kind == "identify") {
      std::string choice = item.structure;
      if (wrongPosition < 0) {
        wrongPosition = item.position;
        choice = item.choices[0] == item.structure ? item.choices[1] : item.choices[0];
      }
      actions.push_back({{"do", "exam_answer"}, {"value", choice}});
    } else {
      REQUIRE(item.kind == "name");
      actions.push_back({{"do", "exam_answer"}, {"value", item.structure}});  // the id, with underscores
    }
  }
  actions.push_back({{"do", "exam_finish"}});
  const Run second = runExamScript(actions, db);
  INFO(second.messages);
  REQUIRE(second.exitCode == 0);
  CHECK(locate3d > 0);
  CHECK(locateSlice > 0);
  REQUIRE(wrongPosition >= 0);

  const auto started = eventsOf(second, "exam_started");
  REQUIRE(started.size() == 1);
  CHECK(started[0].value("resumed", false));
  // Before the results, no event carries a grade.
  bool handedIn = false;
  for (const json& e : second.events) {
    if (e.value("event", "") == "exam_finished") handedIn = true;
    if (!handedIn) CHECK_MESSAGE(!showsGrade(e), e.dump());
  }
  REQUIRE(handedIn);
  CHECK(eventsOf(second, "exam_answered").size() == 12);
  // Every 3-D locate item found a side from which its target can be clicked.
  const auto views = eventsOf(second, "exam_view");
  CHECK(int(views.size()) >= locate3d);
  for (const json& v : views) CHECK_MESSAGE(v.value("target_visible", false), v.dump());
  MESSAGE(locate3d << " locate items in 3-D, " << locateSlice << " on slices; views: " << json(views).dump());
  for (const json& c : eventsOf(second, "click_structure")) CHECK(c.value("visible", false));
  for (const json& c : eventsOf(second, "slice_click_structure")) CHECK(c.value("on_slice", false));

  const auto finished = eventsOf(second, "exam_finished");
  REQUIRE(finished.size() == 1);
  const json& result = finished[0];
  CHECK(result.value("answered", 0) == 12);
  CHECK(result.value("correct", 0) == 11);
  CHECK_FALSE(result.value("time_ran_out", true));
  CHECK(result.value("passed", false));
  CHECK(result.value("score", 0.0) == doctest::Approx(11.0 / 12));
  for (const json& x : result.at("items")) {
    CAPTURE(x.dump());
    CHECK(x.value("correct", false) == (x.value("position", -1) != wrongPosition));
  }

  // The database holds the same: every item answered, the one wrong, the attempt finished and passed.
  for (const StoredItem& item : storedItems(db)) {
    CAPTURE(item.position);
    CHECK(item.answered);
    CHECK(item.correct == (item.position != wrongPosition));
  }
  auto database = at::db::Database::open(db.string());
  REQUIRE(database);
  auto attempt = database->prepare("SELECT finished_at IS NOT NULL, score, passed FROM exam_attempts");
  REQUIRE(attempt);
  auto row = attempt->step();
  REQUIRE(row);
  REQUIRE(*row);
  CHECK(attempt->integer(0) == 1);
  CHECK(attempt->real(1) == doctest::Approx(11.0 / 12));
  CHECK(attempt->integer(2) == 1);
}

TEST_CASE("a desktop exam resumed after its time ran out is handed in with what was answered") {
  TempDir dir("desktop-exam-late");
  const fs::path db = dir / "tutor.db";
  prepareStudent(db);
  // Answer one identify item rightly, leave; then the clock runs out while away.
  const Run first = runExamScript({{{"do", "exam"}, {"exam", kExam}}, {{"do", "exam_leave"}}}, db);
  INFO(first.messages);
  REQUIRE(first.exitCode == 0);
  const auto items = storedItems(db);
  const auto identify = std::find_if(items.begin(), items.end(), [](const StoredItem& i) { return i.kind == "identify"; });
  REQUIRE(identify != items.end());
  const Run answered = runExamScript({{{"do", "exam"}, {"exam", kExam}},
                                      {{"do", "exam_item"}, {"position", identify->position}},
                                      {{"do", "exam_answer"}, {"value", identify->structure}},
                                      {{"do", "exam_leave"}}},
                                     db);
  INFO(answered.messages);
  REQUIRE(answered.exitCode == 0);
  {
    auto database = at::db::Database::open(db.string());
    REQUIRE(database);
    REQUIRE(database->exec("UPDATE exam_attempts SET deadline_at = started_at - 1"));
  }
  const Run late = runExamScript({{{"do", "exam"}, {"exam", kExam}}}, db);
  INFO(late.messages);
  REQUIRE(late.exitCode == 0);
  const auto finished = eventsOf(late, "exam_finished");
  REQUIRE(finished.size() == 1);
  CHECK(finished[0].value("time_ran_out", false));
  CHECK(finished[0].value("answered", 0) == 1);
  CHECK(finished[0].value("correct", 0) == 1);
  CHECK(finished[0].value("score", 1.0) == doctest::Approx(1.0 / 12));
  CHECK_FALSE(finished[0].value("passed", true));
  CHECK(eventsOf(late, "exam_item").empty());  // no item shown after the time is up
}
