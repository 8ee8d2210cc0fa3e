// withSquarePixels (volume/slice_image.h): a slice of anisotropic voxels keeps the anatomy's
// proportions, every output pixel showing the voxel under it; square voxels are left as they are.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "volume/slice_image.h"

using namespace at;

TEST_CASE("withSquarePixels: the picture's sides are in the voxels' proportions and each pixel shows the voxel under it") {
  std::mt19937 random(7);
  std::uniform_int_distribution<int> side(1, 40), byte(0, 255);
  std::uniform_real_distribution<double> mm(0.05, 5.0);
  for (int trial = 0; trial < 200; ++trial) {
    RgbImage image;
    image.width = side(random);
    image.height = side(random);
    image.rgb.resize(std::size_t(image.width * image.height * 3));
    for (auto& c : image.rgb) c = std::uint8_t(byte(random));
    const std::array<double, 2> pixelMm{mm(random), mm(random)};
    double squareMm = 0;
    const RgbImage out = withSquarePixels(image, pixelMm, &squareMm);
    CAPTURE(trial);
    CHECK(squareMm == std::min(pixelMm[0], pixelMm[1]));
    // Extent in mm kept to within one pixel each way.
    CHECK(std::fabs(out.width * squareMm - image.width * pixelMm[0]) <= squareMm);
    CHECK(std::fabs(out.height * squareMm - image.height * pixelMm[1]) <= squareMm);
    CHECK(out.width >= image.width);
    CHECK(out.height >= image.height);
    // Each output pixel's centre, in mm, lies inside the source pixel it copies.
    for (int y = 0; y < out.height; y += 3)
      for (int x = 0; x < out.width; x += 3) {
        const double cx = (x + 0.5) * image.width / out.width, cy = (y + 0.5) * image.height / out.height;
        const int sx = std::min(image.width - 1, int(cx)), sy = std::min(image.height - 1, int(cy));
        for (int c = 0; c < 3; ++c) REQUIRE(out.pixel(x, y)[c] == image.pixel(sx, sy)[c]);
      }
  }
  // Square voxels (within 1 %): the same image.
  RgbImage square;
  square.width = 5;
  square.height = 4;
  square.rgb.assign(60, 9);
  const RgbImage same = withSquarePixels(square, {0.5, 0.504});
  CHECK(same.width == 5);
  CHECK(same.height == 4);
  CHECK(same.rgb == square.rgb);
}
