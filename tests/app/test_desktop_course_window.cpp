// The Course editor window as an instructor sees it: the desktop under Xvfb driven by course_*
// UI-script actions, its screenshots checked for what the window must show — the live validation's
// problem in its red while a step names a structure the dataset lacks, none once the step is gone,
// the preview's heading, and no structure name in the explore panel while a question is previewed
// (the student would see none).
#include <doctest/doctest.h>

#include <algorithm>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "desktop_script.h"
#include "test_support.h"
#include "volume/png_image.h"

namespace fs = std::filesystem;
using at::test::TempDir;
using json = nlohmann::json;

namespace {

// The window's layout at UI scale 1 (ui/desktop_app.cpp, ui/course_editor_panel.cpp): the explore
// panel is 320 px wide on a window under 1200 px; the editor opens at (panel + 60, 60), 34 × 40
// font heights (15 px DejaVu: 510 × 600 px).
constexpr int kWidth = 1000, kHeight = 720, kPanel = 320;
constexpr int kEditorX0 = kPanel + 60, kEditorY0 = 60, kEditorX1 = kEditorX0 + 500, kEditorY1 = kEditorY0 + 590;

struct Box {
  int x0, y0, x1, y1;
};

template <class Is>
int countPixels(const at::RgbImage& img, const Box& box, Is is) {
  int n = 0;
  for (int y = std::max(0, box.y0); y < std::min(img.height, box.y1); ++y)
    for (int x = std::max(0, box.x0); x < std::min(img.width, box.x1); ++x) {
      const std::uint8_t* p = img.pixel(x, y);
      n += is(int(p[0]), int(p[1]), int(p[2]));
    }
  return n;
}

// The editor's problem text (1, 0.5, 0.4) and the orange of names and headings (1, 0.75, 0.3), at
// the cores of their glyphs.
bool problemRed(int r, int g, int b) { return r > 200 && g > 95 && g < 150 && b > 70 && b < 125; }
bool nameOrange(int r, int g, int b) { return r > 200 && g > 160 && g < 215 && b > 45 && b < 110; }

}  // namespace

TEST_CASE("the course editor window shows its problems, then a question's preview with the names hidden") {
  if (!at::test::requireXvfb()) return;
  TempDir dir("desktop-course-window");
  const fs::path problem = dir / "problem.png", preview = dir / "preview.png";
  const json wait = {{"do", "wait_field"}, {"timeout_ms", 120000}};
  const json script = {{"actions", json::array({
      {{"do", "course_new"}, {"id", "window_tour"}, {"title", "Window tour"}},
      {{"do", "select"}, {"structure", "cochlea"}},
      {{"do", "course_show"}, {"title", "The cochlea"}, {"text", "The coiled part of the inner ear."}},
      {{"do", "course_question"}, {"question", {{"kind", "name"}, {"prompt", "Name the highlighted structure."}, {"target", "stapes"}}}},
      {{"do", "course_question"}, {"question", {{"kind", "name"}, {"prompt", "Name it."}, {"target", "pancreas"}}}},
      wait,
      {{"do", "screenshot"}, {"path", problem.string()}},
      {{"do", "course_step"}, {"op", "delete"}, {"index", 2}},
      {{"do", "course_step"}, {"op", "preview"}, {"index", 1}},
      wait,
      {{"do", "screenshot"}, {"path", preview.string()}},
  })}};
  at::test::DesktopOptions options;
  options.dataset = "phantom:64";
  options.size = std::to_string(kWidth) + "x" + std::to_string(kHeight);
  options.db = dir / "c.db";
  const auto run = at::test::runDesktopScript(dir, script, options);
  INFO(run.err);
  REQUIRE(run.exitCode == 0);
  auto a = at::readPng(problem.string()), b = at::readPng(preview.string());
  REQUIRE(a);
  REQUIRE(b);
  REQUIRE(a->width == kWidth);
  REQUIRE(a->height == kHeight);

  // The explore panel below its lessons list (40 % of the window's height, whose lesson titles are
  // orange too) and above its status lines: where the selected structure's name is drawn.
  const Box editor{kEditorX0, kEditorY0, kEditorX1, kEditorY1}, panel{0, kHeight * 52 / 100, kPanel, kHeight - 100};
  const int problemsBefore = countPixels(*a, editor, problemRed), problemsAfter = countPixels(*b, editor, problemRed);
  const int panelNameBefore = countPixels(*a, panel, nameOrange), panelNameAfter = countPixels(*b, panel, nameOrange);
  const int headingBefore = countPixels(*a, editor, nameOrange), headingAfter = countPixels(*b, editor, nameOrange);
  MESSAGE("problem text px " << problemsBefore << " -> " << problemsAfter << "; panel name px " << panelNameBefore << " -> "
                             << panelNameAfter << "; editor orange px " << headingBefore << " -> " << headingAfter);
  // The live validation's line ("lessons[0].steps[2].question.target: no structure 'pancreas' …").
  CHECK(problemsBefore >= 40);
  CHECK(problemsAfter <= problemsBefore / 10);
  // The selected structure's name in the explore panel, then none while the name question is
  // previewed (its target, stapes, is selected and highlighted as the student sees it) …
  CHECK(panelNameBefore >= 20);
  CHECK(panelNameAfter <= panelNameBefore / 10);
  // … and the preview's heading ("Question (name)") in the editor.
  CHECK(headingAfter >= headingBefore + 20);
  const auto previews = at::test::eventsOf(run.events, "course_preview");
  REQUIRE(previews.size() == 1);
  CHECK(previews[0]["names_hidden"] == true);
}
