// An 8-bit RGBA image as the renderer produces it: row 0 is the top row, straight (not
// premultiplied) alpha.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "volume/png_image.h"

namespace at::render {

struct RgbaImage {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgba;  // width · height · 4

  RgbaImage() = default;
  RgbaImage(int w, int h) : width(w), height(h), rgba(std::size_t(w) * std::size_t(h) * 4, 0) {}
  std::array<std::uint8_t, 4> pixel(int x, int y) const {
    const std::size_t o = (std::size_t(y) * std::size_t(width) + std::size_t(x)) * 4;
    return {rgba[o], rgba[o + 1], rgba[o + 2], rgba[o + 3]};
  }
};

// Composites the image over an opaque background colour (0..255 per channel) into 8-bit RGB.
inline RgbImage toRgb(const RgbaImage& image, std::array<std::uint8_t, 3> background = {0, 0, 0}) {
  RgbImage out(image.width, image.height);
  for (std::size_t i = 0, n = std::size_t(image.width) * std::size_t(image.height); i < n; ++i) {
    const unsigned a = image.rgba[i * 4 + 3];
    for (std::size_t c = 0; c < 3; ++c)
      out.rgb[i * 3 + c] = std::uint8_t((image.rgba[i * 4 + c] * a + background[c] * (255 - a) + 127) / 255);
  }
  return out;
}

}  // namespace at::render
