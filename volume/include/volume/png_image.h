// 8-bit RGB images and PNG files (libpng). Used for slices and offscreen renders.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/error.h"

namespace at {

// Row-major, top row first, 3 bytes (R, G, B) per pixel.
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  // width * height * 3

  RgbImage() = default;
  RgbImage(int w, int h) : width(w), height(h), rgb(std::size_t(w) * std::size_t(h) * 3, 0) {}
  std::uint8_t* pixel(int x, int y) { return rgb.data() + (std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3; }
  const std::uint8_t* pixel(int x, int y) const {
    return rgb.data() + (std::size_t(y) * std::size_t(width) + std::size_t(x)) * 3;
  }
};

// Writes an 8-bit RGB PNG. Errors name the file (cannot create, empty image, libpng failure).
Status writePng(const std::string& path, const RgbImage& image);

// Reads any PNG (grey, palette, RGB, with or without alpha, 8 or 16 bit) as 8-bit RGB; alpha is
// dropped. Images over 2^24 pixels (4096x4096; a 4K frame has 8.3 million) or 32768 pixels a
// side are refused before allocation. Errors name the file and the problem.
Result<RgbImage> readPng(const std::string& path);

}  // namespace at
