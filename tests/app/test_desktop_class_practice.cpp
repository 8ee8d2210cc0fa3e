// The desktop under Xvfb tells a student whose answers go to a class server that a locate click in
// its free 3-D view is kept there as practice (the server grades only the pixel picked on the
// picture `play` shows): before she clicks and after, in the terminal's words (class_practice.h),
// on the frame the app drew ("widgets" action). A student on her own machine is told nothing.
#include <doctest/doctest.h>

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "class_practice.h"
#include "db/class_server.h"
#include "desktop_script.h"
#include "test_support.h"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

// inner_ear: four show steps, then "locate the cochlea"; what the panel shows before and after
// the cochlea is clicked.
at::test::DesktopRun locateCochlea(const at::test::TempDir& dir, const fs::path& db) {
  json actions = {{{"do", "lesson"}, {"course", "temporal_bone"}, {"lesson", "inner_ear"}}};
  for (int i = 0; i < 4; ++i) actions.push_back({{"do", "lesson_next"}});
  for (const json& a : json::array({{{"do", "mode"}, {"value", "wdt"}},
                                    {{"do", "view"}, {"value", "superior"}},
                                    {{"do", "wait_field"}},
                                    {{"do", "widgets"}},
                                    {{"do", "click_structure"}, {"structure", "cochlea"}},
                                    {{"do", "widgets"}},
                                    {{"do", "screenshot"}, {"path", (dir / "answered.png").string()}}}))
    actions.push_back(a);
  at::test::DesktopOptions options;
  options.db = db;
  options.user = "tester";
  return at::test::runDesktopScript(dir, {{"actions", actions}}, options);
}

// `inner` lies inside `outer` ([x0, y0, x1, y1], a pixel of slack for rounding).
bool inside(const json& inner, const json& outer) {
  return inner[0].get<double>() >= outer[0].get<double>() - 1 && inner[1].get<double>() >= outer[1].get<double>() - 1 &&
         inner[2].get<double>() <= outer[2].get<double>() + 1 && inner[3].get<double>() <= outer[3].get<double>() + 1;
}

}  // namespace

TEST_CASE("a class member is told before and after a locate click in the desktop that her class server keeps it as practice") {
  if (!at::test::requireXvfb()) return;
  at::test::TempDir dir("desktop-class-practice");
  const fs::path db = dir / "laptop.db";
  {
    // A class whose server is away: her answers wait in the outbox for it, and still count there
    // only as the server grades them.
    auto laptop = at::db::openDatabase(db.string());
    REQUIRE(laptop);
    REQUIRE(at::db::rememberMembership(
        *laptop, {"tester", "K7M2P9QX", "postgresql://tester@127.0.0.1:1/anatomy_class?connect_timeout=1",
                  at::db::ClassRole::Student}));
  }
  const at::test::DesktopRun r = locateCochlea(dir, db);
  INFO(r.err);
  REQUIRE(r.exitCode == 0);
  const auto graded = at::test::eventsOf(r, "graded");
  REQUIRE(graded.size() == 1);
  CHECK(graded[0].value("question", "") == "inner_ear.locate_cochlea");
  CHECK(graded[0].value("class_practice", false));
  const auto frames = at::test::eventsOf(r, "widgets");
  REQUIRE(frames.size() == 2);
  INFO(frames[0].dump());
  INFO(frames[1].dump());
  const json& before = frames[0]["widgets"];
  const json& after = frames[1]["widgets"];
  REQUIRE(before.contains("lesson_practice_ahead"));
  CHECK(before["lesson_practice_ahead"].value("text", "") == "(" + at::app::practiceClickAheadNote() + ")");
  CHECK(inside(before["lesson_practice_ahead"]["rect"], before["lesson_practice_ahead"]["clip"]));
  CHECK_FALSE(before.contains("lesson_practice_kept"));
  REQUIRE(after.contains("lesson_practice_kept"));
  CHECK(after["lesson_practice_kept"].value("text", "") == "(" + at::app::practicePickNote() + ")");
  CHECK(inside(after["lesson_practice_kept"]["rect"], after["lesson_practice_kept"]["clip"]));
  CHECK_FALSE(after.contains("lesson_practice_ahead"));  // answered: nothing more to click
  // The words are the terminal's: what counts on the server is said the same in both notes.
  CHECK(at::app::practicePickNote().find("counts only as the pixel x y picked on the question's picture") != std::string::npos);
  CHECK(at::app::practiceClickAheadNote().find("counts only as the pixel x y picked on the question's picture") !=
        std::string::npos);

  // The answer did go to the class: it waits in the outbox with the lesson's start.
  auto laptop = at::db::openDatabase(db.string());
  REQUIRE(laptop);
  auto counts = at::db::outboxCounts(*laptop);
  REQUIRE(counts);
  CHECK(counts->pending >= 2);
}

TEST_CASE("a student on her own machine is told nothing about a class server around a locate click in the desktop") {
  if (!at::test::requireXvfb()) return;
  at::test::TempDir dir("desktop-local-practice");
  const fs::path db = dir / "laptop.db";
  const at::test::DesktopRun r = locateCochlea(dir, db);
  INFO(r.err);
  REQUIRE(r.exitCode == 0);
  const auto graded = at::test::eventsOf(r, "graded");
  REQUIRE(graded.size() == 1);
  CHECK_FALSE(graded[0].contains("class_practice"));
  const auto frames = at::test::eventsOf(r, "widgets");
  REQUIRE(frames.size() == 2);
  for (const json& frame : frames) {
    INFO(frame.dump());
    CHECK(frame["widgets"].contains("lesson_next"));  // the panel was drawn: the lesson's step is there
    CHECK_FALSE(frame["widgets"].contains("lesson_practice_ahead"));
    CHECK_FALSE(frame["widgets"].contains("lesson_practice_kept"));
  }
  auto laptop = at::db::openDatabase(db.string());
  REQUIRE(laptop);
  auto counts = at::db::outboxCounts(*laptop);
  REQUIRE(counts);
  CHECK(counts->pending == 0);
}
