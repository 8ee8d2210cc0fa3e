// Answers that teach after an exam and after a lesson's wrong answer, in the desktop without a
// window: once an exam is handed in, each item's review row gives the answer given and the right
// one, "show" puts the target up in its own WDT view and "slice" on the axial CT slice through it
// with the target alone in colour; a lesson's "show me" does the same on a slice.
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "desktop_exam_fixtures.h"
#include "headless_desktop.h"
#include "test_support.h"

namespace fs = std::filesystem;
using at::test::TempDir;
using json = nlohmann::json;

namespace {

using Run = at::test::HeadlessRun;
using at::test::eventsOf;

constexpr const char* kExam = "temporal_bone.practical";

Run runScript(const json& actions, const fs::path& db, const std::string& user) {
  return at::test::runPanelScript(actions, db, user);
}

}  // namespace

TEST_CASE("after an exam, each item is reviewed with the answer given, the right one, its view and its slice") {
  TempDir dir("desktop-exam-review");
  const fs::path db = dir / "tutor.db";
  at::test::prepareStudent(db);
  const Run first = runScript({{{"do", "exam"}, {"exam", kExam}}, {{"do", "exam_leave"}}}, db, "examinee");
  INFO(first.messages);
  REQUIRE(first.exitCode == 0);
  const std::vector<at::test::StoredItem> items = at::test::storedItems(db);
  REQUIRE(!items.empty());
  // Every identify item answered with a wrong choice, every name item with a wrong name; the rest
  // left unanswered; handed in; then every item's "show" and "slice" pressed.
  json actions = {{{"do", "exam"}, {"exam", kExam}}};
  int answered = 0;
  for (const at::test::StoredItem& item : items) {
    if (item.kind == "identify") {
      const std::string wrong = item.choices[0] == item.structure ? item.choices[1] : item.choices[0];
      actions.push_back({{"do", "exam_item"}, {"position", item.position}});
      actions.push_back({{"do", "exam_answer"}, {"value", wrong}});
      ++answered;
    } else if (item.kind == "name") {
      actions.push_back({{"do", "exam_item"}, {"position", item.position}});
      actions.push_back({{"do", "exam_answer"}, {"value", "stapes footplate xyz"}});
      ++answered;
    }
  }
  REQUIRE(answered > 0);
  actions.push_back({{"do", "exam_finish"}});
  for (std::size_t i = 0; i < items.size(); ++i) {
    actions.push_back({{"do", "exam_review_item"}, {"index", i}});
    actions.push_back({{"do", "exam_review_item"}, {"index", i}, {"slice", true}});
  }
  const Run r = runScript(actions, db, "examinee");
  INFO(r.messages);
  REQUIRE(r.exitCode == 0);
  const auto finished = eventsOf(r, "exam_finished");
  REQUIRE(finished.size() == 1);
  const json& results = finished[0].at("items");
  REQUIRE(results.size() == items.size());
  const auto reviewed = eventsOf(r, "exam_review_item");
  REQUIRE(reviewed.size() == 2 * items.size());
  const auto slices = eventsOf(r, "answer_slice");
  REQUIRE(slices.size() == items.size());
  for (std::size_t i = 0; i < items.size(); ++i) {
    const at::test::StoredItem& item = items[i];
    INFO("item " << i << " " << item.kind << " " << item.structure);
    const json& result = results[i];
    CHECK_FALSE(result.value("correct", true));       // wrong or unanswered, as given
    CHECK_FALSE(result.value("right_answer", "").empty());
    const bool given = item.kind == "identify" || item.kind == "name";
    CHECK(result.value("answered", !given) == given);
    CHECK(result.value("your_answer", "").empty() == !given);
    if (item.kind == "name") CHECK(result.value("your_answer", "") == "\"stapes footplate xyz\"");
    for (const json& shown : {reviewed[2 * i], reviewed[2 * i + 1]}) {
      CHECK(shown.value("index", -1) == int(i));
      CHECK(shown.value("structure", "") == item.structure);           // the answer, highlighted
      CHECK(shown.value("preset", "") == item.structure + "_wdt");     // in its own WDT view
      CHECK(shown.value("right_answer", "") == result.value("right_answer", "?"));
      CHECK(shown.value("your_answer", "?") == result.value("your_answer", ""));
    }
    CHECK_FALSE(reviewed[2 * i].value("slice", true));
    CHECK(reviewed[2 * i + 1].value("slice", false));
    CHECK(slices[i].value("structure", "") == item.structure);
    CHECK(slices[i].value("width", 0) > 0);
  }
}

TEST_CASE("a lesson's show me on a slice: the target on the axial slice through it") {
  TempDir dir("desktop-show-me-slice");
  const fs::path db = dir / "tutor.db";
  // inner_ear: four show steps, then "Click the cochlea." — clicked wrong, shown on a slice.
  json actions = {{{"do", "lesson"}, {"course", "temporal_bone"}, {"lesson", "inner_ear"}}};
  for (int i = 0; i < 4; ++i) actions.push_back({{"do", "lesson_next"}});
  for (const json& a : json::array({{{"do", "wait_field"}},
                                    {{"do", "click_structure"}, {"structure", "lateral_semicircular_canal"}},
                                    {{"do", "show_me"}, {"slice", true}}}))
    actions.push_back(a);
  const Run r = runScript(actions, db, "learner");
  INFO(r.messages);
  REQUIRE(r.exitCode == 0);
  const auto shown = eventsOf(r, "show_me");
  REQUIRE(shown.size() == 1);
  CHECK(shown[0].value("slice", false));
  const auto slices = eventsOf(r, "answer_slice");
  REQUIRE(slices.size() == 1);
  CHECK(slices[0].value("structure", "") == "cochlea");
  CHECK(slices[0].value("axis", -1) == 2);  // the phantom's k axis runs feet to head
  CHECK(slices[0].value("edges", "") == "left R, right L, top A, bottom P");  // as the Slices panes
}
