#include "slice_marking.h"

#include <algorithm>

namespace at::app {

bool frameStructureOnSlice(RgbImage& image, const LabelMap& labels, const SliceRequest& request, std::uint16_t label,
                           int margin, int thickness) {
  int x0 = image.width, y0 = image.height, x1 = -1, y1 = -1;
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      const auto ijk = sliceVoxelAt(labels.dims(), request, x + 0.5, y + 0.5);
      if (!ijk || labels.at((*ijk)[0], (*ijk)[1], (*ijk)[2]) != label) continue;
      x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
    }
  if (x1 < 0) return false;
  x0 -= margin, y0 -= margin, x1 += margin, y1 += margin;
  const auto paint = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= image.width || y >= image.height) return;
    std::uint8_t* p = image.pixel(x, y);
    p[0] = 255, p[1] = 230, p[2] = 0;
  };
  for (int t = 0; t < thickness; ++t) {
    for (int x = x0 - t; x <= x1 + t; ++x) paint(x, y0 - t), paint(x, y1 + t);
    for (int y = y0 - t; y <= y1 + t; ++y) paint(x0 - t, y), paint(x1 + t, y);
  }
  return true;
}

}  // namespace at::app
