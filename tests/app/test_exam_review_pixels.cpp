// The exam review as the student sees it (the desktop under Xvfb, 1280×720): after an exam is
// handed in, an item's "show" draws its target in the target's own highlight colour where the
// target projects, and "slice" draws the axial slice with the target alone in colour inside the
// yellow frame, in patient orientation. Asserted on the screenshots' pixels, not only on events;
// the screenshots stay in the test's folder for a person to look at.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "desktop_exam_fixtures.h"
#include "desktop_script.h"
#include "headless_desktop.h"
#include "render/preset.h"
#include "test_support.h"
#include "volume/png_image.h"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {

constexpr int kReviewed = 3;  // items whose show and slice are looked at

std::array<double, 3> meanColour(const at::RgbImage& img, int cx, int cy, int r) {
  std::array<double, 3> sum{0, 0, 0};
  int n = 0;
  for (int y = std::max(0, cy - r); y <= std::min(img.height - 1, cy + r); ++y)
    for (int x = std::max(0, cx - r); x <= std::min(img.width - 1, cx + r); ++x) {
      for (int c = 0; c < 3; ++c) sum[std::size_t(c)] += img.pixel(x, y)[c];
      ++n;
    }
  for (double& s : sum) s /= std::max(1, n);
  return sum;
}

// Distance between the chromaticities (r, g, b) / (r + g + b): hue and saturation, not brightness.
double chromaDistance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const double sa = std::max(1.0, a[0] + a[1] + a[2]), sb = std::max(1.0, b[0] + b[1] + b[2]);
  double d = 0;
  for (std::size_t c = 0; c < 3; ++c) d += (a[c] / sa - b[c] / sb) * (a[c] / sa - b[c] / sb);
  return std::sqrt(d);
}

struct Rect {
  int x0, y0, x1, y1;  // [x0, x1) × [y0, y1)
};

bool isFrameYellow(const std::uint8_t* p) { return p[0] > 225 && p[1] > 195 && p[1] < 250 && p[2] < 30; }
bool isLetterYellow(const std::uint8_t* p) { return p[0] > 225 && p[1] > 190 && p[2] >= 25 && p[2] < 90; }
// A label colour over grey: saturated, and neither yellow of the frame or the letters.
bool isColoured(const std::uint8_t* p) {
  const int hi = std::max({p[0], p[1], p[2]}), lo = std::min({p[0], p[1], p[2]});
  return hi - lo > 50 && !isFrameYellow(p) && !isLetterYellow(p);
}

}  // namespace

TEST_CASE("the exam review draws each item's target highlighted in its view and framed on its slice") {
  if (!at::test::requireXvfb()) return;
  at::test::TempDir dir("desktop-exam-review-pixels");
  const fs::path db = dir / "tutor.db";
  at::test::prepareStudent(db);
  // The attempt's items (drawn at random when it starts): started and left without a window,
  // then sat under Xvfb, handed in unanswered — every item reviewed as not right ("(none)").
  {
    at::test::HeadlessOptions headless;
    headless.db = db;
    headless.user = "examinee";
    const auto started = at::test::runHeadless(
        {{"actions", {{{"do", "exam"}, {"exam", "temporal_bone.practical"}}, {{"do", "exam_leave"}}}}}, headless);
    INFO(started.messages);
    REQUIRE(started.exitCode == 0);
  }
  const std::vector<at::test::StoredItem> items = at::test::storedItems(db);
  REQUIRE(items.size() >= std::size_t(kReviewed));
  // The layout once the panels have been drawn (the view's left edge is the panel's width).
  json actions = {{{"do", "exam"}, {"exam", "temporal_bone.practical"}}, {{"do", "exam_finish"}}, {{"do", "layout"}}};
  for (int i = 0; i < kReviewed; ++i) {
    const std::string show = (dir / ("show_" + std::to_string(i) + ".png")).string();
    const std::string slice = (dir / ("slice_" + std::to_string(i) + ".png")).string();
    // The picture first; then where the target projects in that view (hover_structure's event;
    // the hover changes nothing already drawn); then the slice.
    for (const json& a : json::array({{{"do", "exam_review_item"}, {"index", i}},
                                      {{"do", "wait_field"}},
                                      {{"do", "screenshot"}, {"path", show}},
                                      {{"do", "hover_structure"}, {"structure", items[std::size_t(i)].structure}},
                                      {{"do", "exam_review_item"}, {"index", i}, {"slice", true}},
                                      {{"do", "wait_field"}},
                                      {{"do", "screenshot"}, {"path", slice}}}))
      actions.push_back(a);
  }
  const at::test::DesktopRun r = at::test::runLaptopScript(dir, actions, db, "examinee");
  INFO(r.err);
  REQUIRE(r.exitCode == 0);
  // For a person to look at: AT_KEEP_SCREENSHOTS=DIR keeps a copy of each picture.
  if (const char* keep = std::getenv("AT_KEEP_SCREENSHOTS"))
    for (int i = 0; i < kReviewed; ++i)
      for (const std::string kind : {"show_", "slice_"}) {
        const std::string name = kind + std::to_string(i) + ".png";
        if (fs::exists(dir / name))
          fs::copy_file(dir / name, fs::path(keep) / ("exam_review_" + name), fs::copy_options::overwrite_existing);
      }
  const auto layouts = at::test::eventsOf(r, "layout");
  REQUIRE(layouts.size() == 1);
  const json& v = layouts[0]["view"];
  const Rect view{v["x"].get<int>(), v["y"].get<int>(), v["x"].get<int>() + v["width"].get<int>(),
                  v["y"].get<int>() + v["height"].get<int>()};
  const auto reviewed = at::test::eventsOf(r, "exam_review_item");
  REQUIRE(reviewed.size() == std::size_t(2 * kReviewed));
  const auto projected = at::test::eventsOf(r, "hover_structure");
  REQUIRE(projected.size() == std::size_t(kReviewed));
  const auto slices = at::test::eventsOf(r, "answer_slice");
  REQUIRE(slices.size() == std::size_t(kReviewed));
  for (int i = 0; i < kReviewed; ++i) {
    const json& item = reviewed[std::size_t(2 * i)];
    const std::string target = item.value("structure", "");
    INFO("item " << i << ": " << target << " (" << item.dump() << ")");
    CHECK_FALSE(item.value("correct", true));
    CHECK(item.value("your_answer", "?").empty());
    CHECK_FALSE(item.value("right_answer", "").empty());
    // --- "show": the target, in its highlight colour, where it projects.
    auto shot = at::readPng((dir / ("show_" + std::to_string(i) + ".png")).string());
    REQUIRE(shot);
    REQUIRE(shot->width == at::test::kLaptopWidth);
    REQUIRE(shot->height == at::test::kLaptopHeight);
    CHECK(item.value("preset", "") == target + "_wdt");
    const json& where = projected[std::size_t(i)];
    REQUIRE(where.value("structure", "") == target);
    REQUIRE(where.value("visible", false));  // the review's view shows its target
    const int x = int(std::lround(where["x"].get<double>())), y = int(std::lround(where["y"].get<double>()));
    // The colour the target's WDT preset draws it in (the one the review shows, as its event says).
    const at::render::PresetLibrary library(at::test::sourceDir() / "data" / "presets");
    const auto preset = library.load(target + "_wdt");
    REQUIRE(preset);
    const std::array<double, 3> highlight{255.0 * preset->highlightRgb[0], 255.0 * preset->highlightRgb[1],
                                          255.0 * preset->highlightRgb[2]};
    // The view's lit pixels on average (the context) against the target's projected centre.
    std::array<double, 3> context{0, 0, 0};
    int lit = 0;
    for (int py = view.y0; py < view.y1; ++py)
      for (int px = view.x0; px < view.x1; ++px) {
        const std::uint8_t* p = shot->pixel(px, py);
        if (p[0] + p[1] + p[2] <= 3 * 24) continue;
        for (int c = 0; c < 3; ++c) context[std::size_t(c)] += p[c];
        ++lit;
      }
    REQUIRE(lit > 0);
    for (double& c : context) c /= lit;
    const auto atTarget = meanColour(*shot, x, y, 3);
    const double dTarget = chromaDistance(atTarget, highlight), dContext = chromaDistance(context, highlight);
    INFO("at (" << x << ", " << y << ") colour " << atTarget[0] << "," << atTarget[1] << "," << atTarget[2] << " highlight "
                << highlight[0] << "," << highlight[1] << "," << highlight[2] << ": chroma distance " << dTarget
                << ", the view's mean " << dContext);
    CHECK(dTarget < 0.2);  // lit and shaded: its hue, not its brightness (0.05–0.15 seen)
    CHECK(dTarget < 0.5 * dContext);
    // --- "slice": the yellow frame round the target's coloured pixels, nothing coloured outside.
    auto sliceShot = at::readPng((dir / ("slice_" + std::to_string(i) + ".png")).string());
    REQUIRE(sliceShot);
    Rect frame{view.x1, view.y1, view.x0, view.y0};
    int framePixels = 0;
    for (int y = view.y0; y < view.y1; ++y)
      for (int x = view.x0; x < view.x1; ++x)
        if (isFrameYellow(sliceShot->pixel(x, y))) {
          ++framePixels;
          frame = {std::min(frame.x0, x), std::min(frame.y0, y), std::max(frame.x1, x + 1), std::max(frame.y1, y + 1)};
        }
    INFO("frame pixels " << framePixels << " box " << frame.x0 << "," << frame.y0 << " – " << frame.x1 << "," << frame.y1);
    REQUIRE(framePixels > 40);
    // Coloured pixels inside the frame against those outside it, below the window's line of text
    // and buttons, away from the frame's and the edge letters' anti-aliased rims.
    const auto nearLetter = [&](int x, int y) {
      for (int dy = -8; dy <= 8; ++dy)
        for (int dx = -8; dx <= 8; ++dx) {
          const int px = x + dx, py = y + dy;
          if (px >= 0 && py >= 0 && px < sliceShot->width && py < sliceShot->height && isLetterYellow(sliceShot->pixel(px, py)))
            return true;
        }
      return false;
    };
    // The picture's edge letters (R L A P) mark its extent: the region counted.
    Rect letters{view.x1, view.y1, view.x0, view.y0};
    for (int y = view.y0; y < view.y1; ++y)
      for (int x = view.x0; x < view.x1; ++x)
        if (isLetterYellow(sliceShot->pixel(x, y)))
          letters = {std::min(letters.x0, x), std::min(letters.y0, y), std::max(letters.x1, x + 1), std::max(letters.y1, y + 1)};
    INFO("edge letters' box " << letters.x0 << "," << letters.y0 << " – " << letters.x1 << "," << letters.y1);
    REQUIRE(letters.x1 - letters.x0 > 200);  // letters at the left and right edges ...
    REQUIRE(letters.y1 - letters.y0 > 200);  // ... and at the top and bottom
    CHECK(letters.x0 < frame.x0);
    CHECK(letters.x1 > frame.x1);
    CHECK(letters.y0 < frame.y0);
    CHECK(letters.y1 > frame.y1);
    int inside = 0, outside = 0;
    for (int y = letters.y0; y < letters.y1; ++y)
      for (int x = letters.x0; x < letters.x1; ++x) {
        if (!isColoured(sliceShot->pixel(x, y))) continue;
        if (x > frame.x0 && x < frame.x1 - 1 && y > frame.y0 && y < frame.y1 - 1) {
          ++inside;
          continue;
        }
        const bool nearFrame = x > frame.x0 - 8 && x < frame.x1 + 8 && y > frame.y0 - 8 && y < frame.y1 + 8;
        if (!nearFrame && !nearLetter(x, y)) ++outside;
      }
    INFO("coloured pixels inside the frame " << inside << ", outside " << outside);
    CHECK(inside > 0);
    CHECK(outside * 20 <= inside);  // the target alone is in colour
    CHECK(slices[std::size_t(i)].value("structure", "") == target);
    CHECK(slices[std::size_t(i)].value("edges", "") == "left R, right L, top A, bottom P");
  }
}
