#include "slice_marking.h"

#include <algorithm>
#include <cmath>

#include "render/overlay.h"
#include "volume/slice_orientation.h"

namespace at::app {

SliceRequest anchorSliceRequest(const Geometry& grid, const Vec3& anchorMm, int scale) {
  SliceRequest request;
  request.layout = patientSliceLayout(grid.direction, PatientPlane::Axial);
  request.axis = request.layout->sliceAxis;
  const int extent[3] = {grid.dims.x, grid.dims.y, grid.dims.z};
  const double index = grid.patientToIndex(anchorMm)[std::size_t(request.axis)];
  request.index = std::clamp(int(std::lround(index)), 0, std::max(0, extent[request.axis] - 1));
  request.scale = std::max(1, scale);
  return request;
}

void drawSliceEdgeLetters(RgbImage& image, const SliceLayout& layout, int textScale) {
  const render::Rgb yellow{255, 220, 40};
  const int w = 5 * textScale, h = 7 * textScale, pad = 9 * textScale;  // clear of the pictures' pixel rulers
  const auto put = [&](int x, int y, char c) { render::drawText(image, x, y, std::string(1, c), yellow, textScale); };
  put(pad + 7 * textScale, (image.height - h) / 2, layout.left);  // clear of the left ruler's numbers
  put(image.width - pad - w, (image.height - h) / 2, layout.right);
  put((image.width - w) / 2, pad, layout.top);
  put((image.width - w) / 2, image.height - pad - h, layout.bottom);
}

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
