// What a view shows besides the volume (ARCHITECTURE.md §4): an orientation marker (the patient's
// axes as the camera sees them, lettered L/R, P/A, S/I) and a scale bar in millimetres. The
// geometry is for any drawing layer (the desktop draws it with its UI toolkit); drawOverlays
// rasterises both into an image for the `render` command and the figure sheets, with a built-in
// 5 × 7 bitmap font (drawText) that the figure sheets' captions use too.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

#include "render/camera.h"
#include "volume/png_image.h"

namespace at::render {

// One patient axis on screen: the direction its positive end points to (x right, y down), of
// length ≤ 1 (1 in the image plane, shorter when it points towards or away from the viewer), and
// how much it points towards the viewer (−1 … 1, for drawing the nearer end on top).
struct MarkerAxis {
  char positive = 'L', negative = 'R';  // LPS: +x = patient left, +y = posterior, +z = superior
  double dx = 0, dy = 0;
  double towardViewer = 0;
};
std::array<MarkerAxis, 3> orientationMarker(const Camera& camera);

// Millimetres per pixel at the camera's target (the depth the framing sizes the structure at).
double millimetresPerPixel(const Camera& camera, int imageHeight);

// A bar of a round length (1, 2 or 5 × 10^k mm) no longer than `maxFraction` of the image width.
struct ScaleBar {
  double mm = 0;
  double pixels = 0;
  std::string label;  // "2 cm", "5 mm", "0.5 mm", "50 µm", "20 nm" (the unit a reader of that scale uses)
};
ScaleBar scaleBar(const Camera& camera, int imageWidth, int imageHeight, double maxFraction = 0.2);

using Rgb = std::array<std::uint8_t, 3>;

// UTF-8 text with the built-in 5 × 7 font, one glyph per character: printable ASCII, Latin-1
// letters (lower case with their accents, capitals without), units and symbols (µ ° ± × α β σ Δ
// ≤ ≥ → – — … ’ “ ”); any other character, and each byte that is not valid UTF-8, as one '?'.
// Each font pixel is `scale` image pixels, glyphs 6 font pixels apart; (x, y) is the top-left
// corner. Clipped to the image. textWidth counts characters, not bytes.
void drawText(RgbImage& image, int x, int y, std::string_view text, Rgb colour, int scale = 1);
int textWidth(std::string_view text, int scale = 1);
constexpr int kGlyphHeight = 7;
// A line of `width` pixels, its edges smoothed (coverage blended over what is there).
void drawLine(RgbImage& image, double x0, double y0, double x1, double y1, Rgb colour, double width = 1.0);

// The orientation marker in the bottom-left corner and the scale bar in the bottom-right, sized to
// the image (both readable from about 200 pixels up).
void drawOverlays(RgbImage& image, const Camera& camera);

}  // namespace at::render
