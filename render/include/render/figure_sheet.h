// One sheet per paper figure: the panels of a figure side by side, each captioned
// underneath, under a title line, so a reader can compare a whole figure with the paper at once.
// Pure raster work on RgbImage (the captions use overlay.h's bitmap font); `anatomy-tutor
// figure-sheet` and scripts/make_figures.sh build the sheets in docs/figures from rendered panels.
#pragma once

#include <string>
#include <vector>

#include "core/error.h"
#include "volume/png_image.h"

namespace at::render {

struct SheetPanel {
  RgbImage image;
  std::string caption;  // wrapped at word boundaries to the panel's width; '\n' starts a new line
};

struct SheetLayout {
  int columns = 0;       // panels per row; 0: all in one row
  int gap = 12;          // pixels between panels and around the sheet
  int textScale = 2;     // font pixels per glyph pixel (the 5 × 7 font at 2: 14 px high)
};

// The caption's lines wrapped to `widthPx` at the given scale (a word longer than a line is cut).
std::vector<std::string> wrapCaption(const std::string& caption, int widthPx, int textScale);

// Lays out the panels (dark-grey sheet, white title, light-grey captions); panels of different
// sizes are top-aligned in cells as wide as the widest panel; the sheet is at least as wide as its
// title. Error for no panels or an empty image.
Result<RgbImage> composeSheet(const std::string& title, const std::vector<SheetPanel>& panels,
                              const SheetLayout& layout = {});

}  // namespace at::render
