// Figure sheets (render/figure_sheet.h): panels side by side with their captions under a title.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>
#include <string>

#include "core/utf8.h"
#include "render/figure_sheet.h"
#include "render/overlay.h"

using namespace at;
using namespace at::render;

namespace {

RgbImage filled(int w, int h, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  RgbImage im(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      im.pixel(x, y)[0] = r;
      im.pixel(x, y)[1] = g;
      im.pixel(x, y)[2] = b;
    }
  return im;
}

bool hasLightPixels(const RgbImage& im, int x0, int y0, int x1, int y1) {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x)
      if (im.pixel(x, y)[0] > 150) return true;
  return false;
}

}  // namespace

TEST_CASE("FigureSheet_PlacesPanelsSideBySideWithCaptionsBelow") {
  std::vector<SheetPanel> panels{{filled(100, 80, 200, 0, 0), "Red panel"},
                                 {filled(60, 80, 0, 200, 0), "A much longer caption that must wrap"}};
  SheetLayout layout;
  layout.gap = 10;
  layout.textScale = 1;
  auto sheet = composeSheet("Fig. 9", panels, layout);
  REQUIRE(sheet);
  // Two cells as wide as the widest panel, with gaps.
  CHECK(sheet->width == 10 + 2 * (100 + 10));
  const int titleH = (kGlyphHeight + 3) * 2 + 5;
  const int top = 10 + titleH;
  // Panel pixels where they belong: the first at the left, the second in the second cell.
  CHECK(sheet->pixel(10 + 50, top + 40)[0] == 200);
  CHECK(sheet->pixel(120 + 30, top + 40)[1] == 200);
  // The narrower panel's cell is sheet colour right of it.
  CHECK(sheet->pixel(120 + 80, top + 40)[1] < 50);
  // The title is drawn above the panels, captions under them, and the long caption wraps to more
  // lines than the short one.
  CHECK(hasLightPixels(*sheet, 10, 10, 110, top));
  CHECK(hasLightPixels(*sheet, 10, top + 85, 110, top + 95));
  CHECK(wrapCaption("A much longer caption that must wrap", 100, 1).size() >= 2);
  CHECK(wrapCaption("Red panel", 100, 1).size() == 1);
  for (const std::string& line : wrapCaption("A much longer caption that must wrap", 100, 1))
    CHECK(textWidth(line, 1) <= 100);
}

TEST_CASE("FigureSheet_WrapsInRowsAndCutsWordsTooLongForALine") {
  std::vector<SheetPanel> panels(3, SheetPanel{filled(40, 30, 90, 90, 90), "x"});
  SheetLayout layout;
  layout.columns = 2;
  layout.gap = 4;
  auto sheet = composeSheet("", panels, layout);
  REQUIRE(sheet);
  CHECK(sheet->width == 4 + 2 * (40 + 4));
  const auto lines = wrapCaption("abcdefghijklmnopqrstuvwxyz", 40, 1);
  REQUIRE(lines.size() >= 2);
  for (const std::string& l : lines) CHECK(textWidth(l, 1) <= 40);
  CHECK(wrapCaption("one\ntwo", 400, 1).size() == 2);
  // A title wider than the panels widens the sheet rather than being cut.
  const std::string title = "A title much wider than two small panels";
  auto titled = composeSheet(title, panels, layout);
  REQUIRE(titled);
  CHECK(titled->width >= textWidth(title, layout.textScale + 1) + 2 * layout.gap);
}

TEST_CASE("FigureSheet_RefusesNoPanelsOrAnEmptyImage") {
  CHECK_FALSE(composeSheet("t", {}));
  std::vector<SheetPanel> panels{{RgbImage(), "empty"}};
  auto sheet = composeSheet("t", panels);
  REQUIRE_FALSE(sheet);
  CHECK(sheet.error().message.find("panel 1") != std::string::npos);
}

namespace {

// The pixels drawText lights for `text` alone, as a string of 0/1 (one image row after another).
std::string inked(const std::string& text) {
  RgbImage im(std::max(1, textWidth(text, 1)), kGlyphHeight);
  drawText(im, 0, 0, text, Rgb{255, 255, 255}, 1);
  std::string bits;
  for (int y = 0; y < im.height; ++y)
    for (int x = 0; x < im.width; ++x) bits += im.pixel(x, y)[0] > 127 ? '1' : '0';
  return bits;
}

}  // namespace

TEST_CASE("FigureSheet_TextBeyondAsciiIsOneGlyphPerCharacterNotAQuestionMarkPerByte") {
  // A µCT instructor's title: three glyphs, the first not a '?'.
  CHECK(textWidth("µCT", 1) == textWidth("uCT", 1));
  CHECK(inked("µ") != inked("?"));
  CHECK(inked("µ") != inked("u"));
  // Every sign and letter the font claims is its own glyph, none a '?', and accents tell letters apart.
  const std::string drawn[] = {"µ", "μ", "°", "±", "×", "·", "²", "³", "ß", "÷", "α", "β", "σ", "Δ", "–", "—",
                               "…", "’", "“", "”", "→", "←", "≤", "≥", "−", "é", "è", "ê", "ë", "ñ", "ü", "Ö", "ç"};
  for (const std::string& c : drawn) {
    CAPTURE(c);
    CHECK(textWidth(c, 1) == 5);
    CHECK(inked(c) != inked("?"));
  }
  CHECK(inked("é") != inked("e"));
  CHECK(inked("é") != inked("è"));
  CHECK(inked("ï") != inked("i"));
  CHECK(inked("Ö") == inked("O"));  // capitals have no room above them: drawn bare
  // Other scripts and bad bytes: one '?' per character or byte.
  CHECK(inked("耳") == inked("?"));
  CHECK(inked("\xff") == inked("?"));
  CHECK(inked("a\xe8\x80z") == inked("a??z"));
}

TEST_CASE("FigureSheet_WrappedCaptionsNeverCutACharacterAndTitlesKeepTheirSigns") {
  std::mt19937 rng(3);
  const std::string pieces[] = {"a", "b", " ", " ", "µ", "é", "—", "耳", "𝛼", "≥"};
  for (int round = 0; round < 500; ++round) {
    std::string caption;
    const int n = 1 + int(rng() % 40);
    for (int k = 0; k < n; ++k) caption += pieces[rng() % std::size(pieces)];
    const int width = 6 + int(rng() % 60);
    std::string joined;
    for (const std::string& line : wrapCaption(caption, width, 1)) {
      for (std::size_t i = 0; i < line.size(); i += decodeUtf8At(line, i).length) REQUIRE(decodeUtf8At(line, i).valid);
      CHECK((textWidth(line, 1) <= width || utf8Length(line) == 1));
      for (char c : line)
        if (c != ' ') joined += c;
    }
    std::string expected;
    for (char c : caption)
      if (c != ' ') expected += c;
    CHECK(joined == expected);  // nothing lost, nothing split
  }
  // The title's first glyph on a sheet is the micro sign's.
  std::vector<SheetPanel> panels{{filled(200, 40, 0, 0, 0), "0.1 mm"}};
  SheetLayout layout;
  layout.gap = 8;
  layout.textScale = 1;
  auto sheet = composeSheet("µCT-like", panels, layout);
  REQUIRE(sheet);
  RgbImage alone(20, kGlyphHeight * 2);
  std::string onSheet, expected;
  drawText(alone, 0, 0, "µ", Rgb{255, 255, 255}, 2);
  for (int y = 0; y < kGlyphHeight * 2; ++y)
    for (int x = 0; x < 10; ++x) {
      onSheet += sheet->pixel(8 + x, 8 + y)[0] > 127 ? '1' : '0';
      expected += alone.pixel(x, y)[0] > 127 ? '1' : '0';
    }
  CHECK(onSheet == expected);
}

// The scale bar is a round length no wider than a fifth of the picture, labelled in the unit a
// reader of that scale uses, at every scale from a whole CT to a nanometre µCT.
TEST_CASE("ScaleBar_ReadsInCmMmMicrometresOrNanometres_AtEveryScale") {
  Camera camera;
  const double halfHeightPerMm = std::tan(camera.fovYDeg * 3.14159265358979323846 / 360.0);
  const std::vector<std::pair<double, std::string>> cases = {
      {300.0, "cm"}, {30.0, "cm"},  {3.0, "mm"},  {0.6, "mm"},  {0.3, "mm"},
      {0.1, "µm"},   {0.03, "µm"},  {3e-3, "µm"}, {3e-4, "nm"}, {3e-6, "nm"}};
  for (const auto& [halfHeightMm, unit] : cases) {
    CAPTURE(halfHeightMm);
    camera.distanceMm = halfHeightMm / halfHeightPerMm;
    const ScaleBar bar = scaleBar(camera, 400, 400);
    CAPTURE(bar.label);
    const double mmPerPixel = millimetresPerPixel(camera, 400);
    CHECK(bar.pixels <= 0.2 * 400 + 1e-6);
    CHECK(bar.pixels >= 0.2 * 400 / 5.0 - 1e-6);  // 1, 2 or 5 × 10^k: at least a fifth of the room
    CHECK(bar.mm == doctest::Approx(bar.pixels * mmPerPixel));
    CHECK(bar.label.size() > unit.size() + 1);
    CHECK(bar.label.compare(bar.label.size() - unit.size(), unit.size(), unit) == 0);
    // The number before the unit times the unit is the bar's length.
    const double number = std::stod(bar.label);
    const double scale = unit == "cm" ? 10 : unit == "mm" ? 1 : unit == "µm" ? 1e-3 : 1e-6;
    CHECK(number * scale == doctest::Approx(bar.mm));
  }
}
