// The desktop app as a user sees it: scripted runs under Xvfb (Mesa) whose screenshots are checked
// for semantic properties, and the no-display fallback of `anatomy-tutor` without arguments.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include "desktop_script.h"
#include "test_support.h"
#include "volume/png_image.h"

namespace fs = std::filesystem;
using at::test::TempDir;
using json = nlohmann::json;

namespace {

constexpr int kPanel = 320;  // the explore panel's width at UI scale 1 (the view lies right of it)

using Run = at::test::DesktopRun;

// Runs `script` on the 128³ phantom in an 800×480 window with the volume at 0.4 of the view's
// resolution (software GL on two shared cores is slow).
Run runScript(const TempDir& dir, const json& script, const std::string& screenshot) {
  at::test::DesktopOptions options;
  options.screenshot = screenshot;
  return at::test::runDesktopScript(dir, script, options);
}

const json* findEvent(const Run& r, const std::string& kind) {
  for (const json& e : r.events)
    if (e.is_object() && e.value("event", "") == kind) return &e;
  return nullptr;
}

// Mean colour of a (2r+1)² window.
std::array<double, 3> meanColour(const at::RgbImage& img, int cx, int cy, int r) {
  std::array<double, 3> sum{0, 0, 0};
  int n = 0;
  for (int y = std::max(0, cy - r); y <= std::min(img.height - 1, cy + r); ++y)
    for (int x = std::max(0, cx - r); x <= std::min(img.width - 1, cx + r); ++x) {
      const std::uint8_t* p = img.pixel(x, y);
      for (int c = 0; c < 3; ++c) sum[std::size_t(c)] += p[c];
      ++n;
    }
  for (double& s : sum) s /= std::max(1, n);
  return sum;
}

// Pixels of the volume view that differ from the dark background.
int litPixels(const at::RgbImage& img) {
  int n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = kPanel; x < img.width; ++x) {
      const std::uint8_t* p = img.pixel(x, y);
      if (p[0] + p[1] + p[2] > 3 * 24) ++n;
    }
  return n;
}

// Distance between the chromaticities (r, g, b) / (r + g + b) of two colours.
double chromaDistance(const std::array<double, 3>& a, const std::array<double, 3>& b) {
  const double sa = std::max(1.0, a[0] + a[1] + a[2]), sb = std::max(1.0, b[0] + b[1] + b[2]);
  double d = 0;
  for (std::size_t c = 0; c < 3; ++c) d += (a[c] / sa - b[c] / sb) * (a[c] / sa - b[c] / sb);
  return std::sqrt(d);
}

}  // namespace

TEST_CASE("the desktop app's default view under Xvfb shows the volume, an orientation marker and a scale bar") {
  if (!at::test::requireXvfb()) return;
  TempDir dir("desktop-default");
  const fs::path shot = dir / "default.png";
  const Run r = runScript(dir, json{{"actions", json::array()}}, shot.string());
  INFO(r.err);
  REQUIRE(r.exitCode == 0);
  const json* ctx = findEvent(r, "context");
  REQUIRE(ctx != nullptr);
  MESSAGE("GL: " << ctx->value("gl", "?"));
  auto img = at::readPng(shot.string());
  REQUIRE(img);
  CHECK(img->width == 800);
  CHECK(img->height == 480);
  // A fifth of the view at least is the rendered volume, not background.
  CHECK(litPixels(*img) > (800 - kPanel) * 480 / 5);
  // The orientation marker in the view's bottom-left corner: at least two of its three axes
  // (L/R red, P/A green, S/I blue; one may point at the viewer) in colours the volume does not have.
  int axesSeen = 0;
  for (int axis = 0; axis < 3; ++axis) {
    int n = 0;
    for (int y = 480 - 110; y < 480; ++y)
      for (int x = kPanel; x < kPanel + 110; ++x) {
        const std::uint8_t* p = img->pixel(x, y);
        const int c = p[axis], o1 = p[(axis + 1) % 3], o2 = p[(axis + 2) % 3];
        n += c > 150 && c > o1 + 50 && c > o2 + 50 && std::abs(o1 - o2) < 60;  // not the orange highlight
      }
    axesSeen += n >= 10;
  }
  CHECK(axesSeen >= 2);
  // The scale bar in the bottom-right corner: a white horizontal line at least 15 pixels long.
  int longestRun = 0;
  for (int y = 480 - 40; y < 480; ++y)
    for (int x = 800 - 160, run = 0; x < 800; ++x) {
      const std::uint8_t* p = img->pixel(x, y);
      run = (p[0] > 200 && p[1] > 200 && p[2] > 200) ? run + 1 : 0;
      longestRun = std::max(longestRun, run);
    }
  CHECK(longestRun >= 15);
}

TEST_CASE("hovering a structure's projected centroid shows its highlight there, and bare mode drops the context") {
  if (!at::test::requireXvfb()) return;
  TempDir dir("desktop-hover");
  const fs::path before = dir / "before.png", after = dir / "after.png", bare = dir / "bare.png";
  // Select one structure, frame the view on it, then hover another one that the view shows.
  const json script = {{"actions",
                        {{{"do", "select"}, {"structure", "vestibule"}},
                         {{"do", "view"}, {"value", "lateral_right"}},
                         {{"do", "zoom"}, {"factor", 0.45}},
                         {{"do", "wait_field"}},
                         {{"do", "screenshot"}, {"path", before.string()}},
                         {{"do", "hover_structure"}, {"structure", "temporal_line"}},
                         {{"do", "wait_field"}},
                         {{"do", "screenshot"}, {"path", after.string()}},
                         {{"do", "mode"}, {"value", "bare"}},
                         {{"do", "wait_field"}},
                         {{"do", "screenshot"}, {"path", bare.string()}}}}};
  const Run r = runScript(dir, script, "");
  INFO(r.err);
  REQUIRE(r.exitCode == 0);
  const json* hs = findEvent(r, "hover_structure");
  REQUIRE(hs != nullptr);
  REQUIRE(hs->value("visible", false));
  const int x = int(std::lround(hs->at("x").get<double>())), y = int(std::lround(hs->at("y").get<double>()));
  const json* hover = findEvent(r, "hover");
  REQUIRE(hover != nullptr);
  INFO("picked " << hover->dump());
  CHECK(hover->value("structure", "") == "temporal_line");
  REQUIRE(hover->contains("highlight_rgb"));
  const std::array<double, 3> highlight{255 * hover->at("highlight_rgb")[0].get<double>(),
                                        255 * hover->at("highlight_rgb")[1].get<double>(),
                                        255 * hover->at("highlight_rgb")[2].get<double>()};
  auto a = at::readPng(before.string()), b = at::readPng(after.string()), c = at::readPng(bare.string());
  REQUIRE(a);
  REQUIRE(b);
  REQUIRE(c);
  const auto colourBefore = meanColour(*a, x, y, 4), colourAfter = meanColour(*b, x, y, 4);
  INFO("before " << colourBefore[0] << "," << colourBefore[1] << "," << colourBefore[2] << "  after " << colourAfter[0]
                 << "," << colourAfter[1] << "," << colourAfter[2]);
  // Where the hovered structure projects, the colour turns towards its highlight colour (compared as
  // chromaticity: the share of each channel, so that shading and brightness do not matter).
  const double before_ = chromaDistance(colourBefore, highlight), after_ = chromaDistance(colourAfter, highlight);
  INFO("chromaticity distance to the highlight: before " << before_ << ", after " << after_);
  CHECK(after_ < 0.6 * before_);
  // Bare mode: the structure alone, far fewer lit pixels than with its WDT context.
  const int withContext = litPixels(*b), alone = litPixels(*c);
  INFO("lit pixels: context " << withContext << ", bare " << alone);
  CHECK(alone > 0);
  CHECK(alone * 2 < withContext);
}

TEST_CASE("without a display, anatomy-tutor says so in one line and writes the default lesson's views") {
  // No display named at all, or one named that does not answer (a stopped X server).
  const char* environment = "env -u DISPLAY -u WAYLAND_DISPLAY";
  SUBCASE("no display named") {}
  SUBCASE("a display named that cannot be opened") { environment = "env -u WAYLAND_DISPLAY DISPLAY=:87"; }
  TempDir dir("desktop-nodisplay");
  const fs::path out = dir / "stdout", err = dir / "stderr";
  const std::string cmd = "cd '" + dir.path().string() + "' && " + environment + " '" +
                          at::test::appBinary().string() + "' >'" + out.string() + "' 2>'" + err.string() + "'";
  const int status = std::system(cmd.c_str());
  const std::string text = at::test::readFile(out);
  INFO(text << at::test::readFile(err));
  REQUIRE(WIFEXITED(status));
  if (WEXITSTATUS(status) != 0 && at::test::readFile(err).find("offscreen rendering") != std::string::npos) {
    at::test::skipf("no EGL offscreen context here");
    return;
  }
  REQUIRE(WEXITSTATUS(status) == 0);
  CHECK(text.rfind("anatomy-tutor: no display", 0) == 0);
  int pngs = 0;
  for (const auto& entry : fs::directory_iterator(dir / "anatomy-tutor-views")) {
    if (entry.path().extension() != ".png") continue;
    auto img = at::readPng(entry.path().string());
    REQUIRE(img);
    int lit = 0;
    for (std::size_t i = 0; i + 2 < img->rgb.size(); i += 3) lit += img->rgb[i] + img->rgb[i + 1] + img->rgb[i + 2] > 72;
    CHECK(lit > img->width * img->height / 50);
    ++pngs;
  }
  CHECK(pngs >= 2);
}
