#include "volume/slice_image.h"

#include <algorithm>
#include <cmath>

namespace at {
namespace {

struct SliceAxes {
  int axis = 2, u = 0, v = 1;
  bool flipU = false, flipV = false;
};

SliceAxes axesOf(const SliceRequest& r) {
  const SliceLayout l = r.layout ? *r.layout : voxelSliceLayout(r.axis);
  return {l.sliceAxis, l.columnAxis, l.rowAxis, l.columnReversed, l.rowReversed};
}

double srgbEncode(double linear) {
  linear = std::clamp(linear, 0.0, 1.0);
  return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

}  // namespace

Result<RgbImage> renderSlice(const Volume& volume, const LabelMap* labels, const std::vector<Structure>& structures,
                             const SliceRequest& r) {
  const Dims& d = volume.dims();
  const int extent[3] = {d.x, d.y, d.z};
  const int axis = r.layout ? r.layout->sliceAxis : r.axis;
  if (axis < 0 || axis > 2) return fail("slice axis must be 0, 1 or 2 (x, y, z)");
  if (r.index < 0 || r.index >= extent[axis])
    return fail("slice index " + std::to_string(r.index) + " is outside 0 … " + std::to_string(extent[axis] - 1));
  if (!(r.windowWidthHu > 0)) return fail("slice window width must be > 0 HU");
  if (r.scale < 1) return fail("slice scale must be at least 1");
  const SliceAxes a = axesOf(r);
  std::vector<std::array<std::uint8_t, 3>> colours(65536, {0, 0, 0});
  std::vector<bool> known(65536, false);
  for (const Structure& s : structures) {
    for (int c = 0; c < 3; ++c)
      colours[s.label][std::size_t(c)] = std::uint8_t(std::lround(255 * srgbEncode(s.colour[std::size_t(c)])));
    known[s.label] = true;
  }
  const bool overlay = labels && !labels->empty() && r.labelAlpha > 0;
  const double lo = r.windowCentreHu - r.windowWidthHu / 2;
  RgbImage image(extent[a.u] * r.scale, extent[a.v] * r.scale);
  for (int row = 0; row < extent[a.v]; ++row)
    for (int col = 0; col < extent[a.u]; ++col) {
      int ijk[3];
      ijk[a.axis] = r.index;
      ijk[a.u] = a.flipU ? extent[a.u] - 1 - col : col;
      ijk[a.v] = a.flipV ? extent[a.v] - 1 - row : row;
      const double hu = volume.at(ijk[0], ijk[1], ijk[2]);
      const double grey = std::clamp((hu - lo) / r.windowWidthHu, 0.0, 1.0) * 255.0;
      const std::uint16_t label = overlay ? labels->at(ijk[0], ijk[1], ijk[2]) : 0;
      std::uint8_t value[3];
      for (int c = 0; c < 3; ++c) {
        double v = grey;
        if (label != 0 && known[label]) v = (1 - r.labelAlpha) * grey + r.labelAlpha * colours[label][std::size_t(c)];
        value[c] = std::uint8_t(std::lround(std::clamp(v, 0.0, 255.0)));
      }
      for (int dy = 0; dy < r.scale; ++dy)
        for (int dx = 0; dx < r.scale; ++dx) std::copy(value, value + 3, image.pixel(col * r.scale + dx, row * r.scale + dy));
    }
  return image;
}

std::optional<std::array<int, 3>> sliceVoxelAt(const Dims& d, const SliceRequest& r, double x, double y) {
  const int extent[3] = {d.x, d.y, d.z};
  const int axis = r.layout ? r.layout->sliceAxis : r.axis;
  if (axis < 0 || axis > 2 || r.scale < 1 || x < 0 || y < 0) return std::nullopt;
  const SliceAxes a = axesOf(r);
  const int col = int(x) / r.scale, row = int(y) / r.scale;
  if (col >= extent[a.u] || row >= extent[a.v]) return std::nullopt;
  std::array<int, 3> ijk{};
  ijk[std::size_t(a.axis)] = r.index;
  ijk[std::size_t(a.u)] = a.flipU ? extent[a.u] - 1 - col : col;
  ijk[std::size_t(a.v)] = a.flipV ? extent[a.v] - 1 - row : row;
  return ijk;
}

RgbImage withSquarePixels(const RgbImage& image, std::array<double, 2> pixelMm, double* squareMm) {
  const double side = std::min(pixelMm[0], pixelMm[1]);
  if (squareMm) *squareMm = side;
  if (!(side > 0) || image.width <= 0 || image.height <= 0) return image;
  // Within 1 %: already square (rounding would only repeat a column or a row somewhere).
  const double sx = pixelMm[0] / side, sy = pixelMm[1] / side;
  if (sx < 1.01 && sy < 1.01) return image;
  RgbImage out;
  out.width = std::max(1, int(std::lround(image.width * sx)));
  out.height = std::max(1, int(std::lround(image.height * sy)));
  out.rgb.resize(std::size_t(out.width) * std::size_t(out.height) * 3);
  for (int y = 0; y < out.height; ++y) {
    const int from = std::min(image.height - 1, int((y + 0.5) * image.height / out.height));
    for (int x = 0; x < out.width; ++x) {
      const int column = std::min(image.width - 1, int((x + 0.5) * image.width / out.width));
      std::copy_n(image.pixel(column, from), 3, out.pixel(x, y));
    }
  }
  return out;
}

}  // namespace at
