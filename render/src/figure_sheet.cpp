#include "render/figure_sheet.h"

#include <algorithm>
#include <cstring>
#include <sstream>

#include "core/utf8.h"
#include "render/overlay.h"

namespace at::render {

namespace {

constexpr Rgb kSheet{24, 24, 26};
constexpr Rgb kTitle{245, 245, 245};
constexpr Rgb kCaption{200, 200, 200};

int lineHeight(int scale) { return (kGlyphHeight + 3) * scale; }

}  // namespace

std::vector<std::string> wrapCaption(const std::string& caption, int widthPx, int textScale) {
  std::vector<std::string> lines;
  std::istringstream paragraphs(caption);
  std::string paragraph;
  while (std::getline(paragraphs, paragraph)) {
    std::istringstream words(paragraph);
    std::string word, line;
    while (words >> word) {
      // Cut what cannot fit, between characters (never inside a UTF-8 sequence).
      while (textWidth(word, textScale) > widthPx && utf8Length(word) > 1) {
        std::size_t n = utf8Length(word) - 1;
        while (n > 1 && textWidth(utf8Prefix(word, n), textScale) > widthPx) --n;
        if (!line.empty()) lines.push_back(std::move(line));
        line.clear();
        const std::string head(utf8Prefix(word, n));
        word = word.substr(head.size());
        lines.push_back(head);
      }
      const std::string joined = line.empty() ? word : line + " " + word;
      if (textWidth(joined, textScale) <= widthPx) {
        line = joined;
      } else {
        lines.push_back(std::move(line));
        line = word;
      }
    }
    lines.push_back(std::move(line));
  }
  while (!lines.empty() && lines.back().empty()) lines.pop_back();
  return lines;
}

Result<RgbImage> composeSheet(const std::string& title, const std::vector<SheetPanel>& panels,
                              const SheetLayout& layout) {
  if (panels.empty()) return fail("figure sheet: no panels");
  int cellW = 0, cellH = 0;
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const RgbImage& im = panels[i].image;
    if (im.width <= 0 || im.height <= 0 || im.rgb.size() != std::size_t(im.width) * std::size_t(im.height) * 3)
      return fail("figure sheet: panel " + std::to_string(i + 1) + " has no image");
    cellW = std::max(cellW, im.width);
    cellH = std::max(cellH, im.height);
  }
  const int scale = std::max(1, layout.textScale), gap = std::max(0, layout.gap);
  const int columns = layout.columns > 0 ? std::min<int>(layout.columns, int(panels.size())) : int(panels.size());
  const int rows = (int(panels.size()) + columns - 1) / columns;
  std::size_t captionLines = 0;
  std::vector<std::vector<std::string>> wrapped;
  for (const SheetPanel& p : panels) {
    wrapped.push_back(wrapCaption(p.caption, cellW, scale));
    captionLines = std::max(captionLines, wrapped.back().size());
  }
  const int titleH = title.empty() ? 0 : lineHeight(scale + 1) + gap / 2;
  const int rowH = cellH + gap / 2 + int(captionLines) * lineHeight(scale);
  const int titleW = title.empty() ? 0 : 2 * gap + textWidth(title, scale + 1);  // a title is never cut
  RgbImage sheet(std::max(gap + columns * (cellW + gap), titleW), gap + titleH + rows * (rowH + gap));
  for (std::size_t i = 0; i < sheet.rgb.size(); i += 3) std::memcpy(&sheet.rgb[i], kSheet.data(), 3);
  if (!title.empty()) drawText(sheet, gap, gap, title, kTitle, scale + 1);
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const int x0 = gap + int(i) % columns * (cellW + gap);
    const int y0 = gap + titleH + int(i) / columns * (rowH + gap);
    const RgbImage& im = panels[i].image;
    for (int y = 0; y < im.height; ++y)
      std::memcpy(sheet.pixel(x0, y0 + y), im.pixel(0, y), std::size_t(im.width) * 3);
    int ty = y0 + cellH + gap / 2;
    for (const std::string& line : wrapped[i]) {
      drawText(sheet, x0, ty, line, kCaption, scale);
      ty += lineHeight(scale);
    }
  }
  return sheet;
}

}  // namespace at::render
