// An 8-bit RGBA image as the renderer produces it: row 0 is the top row, straight (not
// premultiplied) alpha.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

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

}  // namespace at::render
