// The slice "show me on a slice" and a locate-on-slice exam item show (services/slice_marking.h):
// for any grid orientation (axes permuted and flipped), the picture is the axial plane through
// the anchor in patient orientation — every pixel on the anchor's superior–inferior level, the
// patient's left to the right, posterior down — and its edge letters say so.
#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <random>

#include "slice_marking.h"
#include "volume/slice_image.h"
#include "volume/slice_orientation.h"
#include "test_support.h"

using namespace at;

namespace {

// A direction matrix whose voxel axis i points along patient axis perm[i], with sign sign[i].
Mat3 permutedDirection(const std::array<int, 3>& perm, const std::array<int, 3>& sign) {
  Mat3 m;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m.m[std::size_t(r)][std::size_t(c)] = 0;
  for (int i = 0; i < 3; ++i) m.m[std::size_t(perm[std::size_t(i)])][std::size_t(i)] = sign[std::size_t(i)];
  return m;
}

}  // namespace

TEST_CASE("the anchor's slice is axial in patient orientation for every grid orientation, as the Slices panes lay it out") {
  const std::uint64_t seed = test::freshSeed("anchor slice orientations");
  INFO("seed " << seed);
  std::mt19937 rng{unsigned(seed)};
  std::array<int, 3> perm{0, 1, 2};
  int checked = 0;
  do {
    for (int signs = 0; signs < 8; ++signs) {
      const std::array<int, 3> sign{signs & 1 ? -1 : 1, signs & 2 ? -1 : 1, signs & 4 ? -1 : 1};
      Geometry g;
      g.dims = {int(rng() % 9) + 4, int(rng() % 9) + 4, int(rng() % 9) + 4};
      g.spacingMm = {0.5 + (rng() % 4) * 0.25, 0.5 + (rng() % 4) * 0.25, 0.5 + (rng() % 4) * 0.25};
      g.originMm = {double(int(rng() % 41) - 20), double(int(rng() % 41) - 20), double(int(rng() % 41) - 20)};
      g.direction = permutedDirection(perm, sign);
      const std::array<int, 3> anchorVoxel{int(rng() % unsigned(g.dims.x)), int(rng() % unsigned(g.dims.y)),
                                           int(rng() % unsigned(g.dims.z))};
      const Vec3 anchorMm = g.indexToPatient({double(anchorVoxel[0]), double(anchorVoxel[1]), double(anchorVoxel[2])});
      INFO("perm " << perm[0] << perm[1] << perm[2] << " signs " << signs);
      const SliceRequest r = app::anchorSliceRequest(g, anchorMm, 2);
      REQUIRE(r.layout.has_value());
      // The one rule the Slices panes use.
      const SliceLayout panes = patientSliceLayout(g.direction, PatientPlane::Axial);
      CHECK(r.layout->edgeLetters() == panes.edgeLetters());
      CHECK(r.layout->edgeLetters() == "left R, right L, top A, bottom P");
      CHECK(r.axis == r.layout->sliceAxis);
      CHECK(r.index == anchorVoxel[std::size_t(r.axis)]);
      const int extent[3] = {g.dims.x, g.dims.y, g.dims.z};
      const int w = extent[r.layout->columnAxis] * r.scale, h = extent[r.layout->rowAxis] * r.scale;
      // Pixel centres: all on the anchor's S level; x grows toward the patient's left (+L),
      // y toward posterior (+P).
      std::array<double, 3> previous{};
      for (int y = 0; y < h; y += r.scale)
        for (int x = 0; x < w; x += r.scale) {
          const auto ijk = sliceVoxelAt(g.dims, r, x + 0.5, y + 0.5);
          REQUIRE(ijk.has_value());
          const Vec3 p = g.indexToPatient({double((*ijk)[0]), double((*ijk)[1]), double((*ijk)[2])});
          CHECK(std::abs(p[2] - anchorMm[2]) < 1e-9);
          if (x > 0) CHECK(p[0] > previous[0]);
          if (x == 0 && y > 0) CHECK(p[1] > previous[1]);
          previous = {p[0], p[1], p[2]};
          ++checked;
        }
    }
  } while (std::next_permutation(perm.begin(), perm.end()));
  CHECK(checked > 0);
}

TEST_CASE("the slice picture's edge letters are drawn at the middle of its four edges") {
  RgbImage image(160, 140);
  const SliceLayout layout = patientSliceLayout(Mat3::identity(), PatientPlane::Axial);
  app::drawSliceEdgeLetters(image, layout, 2);
  const auto litIn = [&](int x0, int y0, int x1, int y1) {
    int lit = 0;
    for (int y = std::max(0, y0); y < std::min(image.height, y1); ++y)
      for (int x = std::max(0, x0); x < std::min(image.width, x1); ++x)
        if (image.pixel(x, y)[0] > 200) ++lit;
    return lit;
  };
  const int total = litIn(0, 0, image.width, image.height);
  CHECK(total > 0);
  const int left = litIn(0, 45, 50, 95), right = litIn(110, 45, 160, 95), top = litIn(50, 0, 110, 45),
            bottom = litIn(50, 95, 110, 140);
  CHECK(left > 0);
  CHECK(right > 0);
  CHECK(top > 0);
  CHECK(bottom > 0);
  CHECK(left + right + top + bottom == total);  // nothing in the corners or the middle
  // Different letters, different glyphs (R is not L, A is not P).
  CHECK(left != right);
  CHECK(top != bottom);
}
