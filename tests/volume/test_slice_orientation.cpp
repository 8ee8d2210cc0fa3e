// Slice pictures in patient orientation (volume/slice_orientation.h): the edge letters say where
// the picture really goes in the patient for any voxel order, and a NIfTI label map shows the same
// picture as the DICOM series it was made on although its rows and slices run the other way.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <tuple>
#include <random>

#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/image_file.h"
#include "volume/slice_image.h"
#include "volume/slice_orientation.h"

using namespace at;

namespace {

// The LPS letter of the largest component of a patient displacement.
char letterOf(const Vec3& d) {
  int best = 0;
  for (int p = 1; p < 3; ++p)
    if (std::abs(d[std::size_t(p)]) > std::abs(d[std::size_t(best)])) best = p;
  static const char pos[3] = {'L', 'P', 'S'}, neg[3] = {'R', 'A', 'I'};
  return d[std::size_t(best)] >= 0 ? pos[best] : neg[best];
}

// Patient point (mm) shown at the centre of pixel (x, y) of a scale-1 picture.
Vec3 pointAt(const Geometry& g, const SliceRequest& r, int x, int y) {
  const auto v = sliceVoxelAt(g.dims, r, x + 0.5, y + 0.5);
  REQUIRE(v);
  return g.indexToPatient({double((*v)[0]), double((*v)[1]), double((*v)[2])});
}

// The letters of `layout` are where one pixel right / down moves in the patient.
void checkLettersFollowGeometry(const Geometry& g, const SliceLayout& layout) {
  SliceRequest r;
  r.layout = layout;
  r.index = 0;
  const Vec3 p = pointAt(g, r, 0, 0);
  CHECK(letterOf(pointAt(g, r, 1, 0) - p) == layout.right);
  CHECK(letterOf(p - pointAt(g, r, 1, 0)) == layout.left);
  CHECK(letterOf(pointAt(g, r, 0, 1) - p) == layout.bottom);
  CHECK(letterOf(p - pointAt(g, r, 0, 1)) == layout.top);
}

}  // namespace

TEST_CASE("patient slice layouts: radiological letters for LPS, RAS and any signed permutation of axes") {
  // The convention is the same whatever the voxel order: (left, right, top, bottom) per plane.
  const std::string expected[3] = {"APSI", "RLSI", "RLAP"};  // sagittal, coronal, axial
  Mat3 ras;
  ras.m = {{{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}}};
  const std::uint64_t seed = test::freshSeed("slice orientation signed permutations");
  std::mt19937_64 rng(seed);
  std::vector<Mat3> directions{Mat3::identity(), ras};
  for (int n = 0; n < 40; ++n) {  // random signed permutations, a few slightly oblique
    int perm[3] = {0, 1, 2};
    std::shuffle(perm, perm + 3, rng);
    Mat3 d;
    d.m = {{{0, 0, 0}, {0, 0, 0}, {0, 0, 0}}};
    for (int c = 0; c < 3; ++c) d.m[std::size_t(perm[c])][std::size_t(c)] = (rng() & 1) ? 1.0 : -1.0;
    if (n % 4 == 0) {  // a 10° tilt about patient z
      const double a = 10 * M_PI / 180;
      Mat3 rot;
      rot.m = {{{std::cos(a), -std::sin(a), 0}, {std::sin(a), std::cos(a), 0}, {0, 0, 1}}};
      d = rot * d;
    }
    directions.push_back(d);
  }
  for (std::size_t n = 0; n < directions.size(); ++n) {
    Geometry g;
    g.dims = {7, 5, 4};
    g.spacingMm = {0.8, 1.1, 2.5};
    g.originMm = {-3, 12, 40};
    g.direction = directions[n];
    for (int plane = 0; plane < 3; ++plane) {
      CAPTURE(n);
      CAPTURE(plane);
      CAPTURE(seed);
      const SliceLayout l = patientSliceLayout(g.direction, PatientPlane(plane));
      CHECK(std::string{l.left, l.right, l.top, l.bottom} == expected[plane]);
      // The three voxel axes are used once each.
      CHECK(l.sliceAxis + l.columnAxis + l.rowAxis == 3);
      CHECK(l.sliceAxis != l.columnAxis);
      CHECK(l.rowAxis != l.columnAxis);
      checkLettersFollowGeometry(g, l);
      checkLettersFollowGeometry(g, voxelSliceLayout(plane, g.direction));
    }
  }
  // LPS data: patient layout is the voxel layout `slice --axis` always drew.
  for (int axis = 0; axis < 3; ++axis) {
    const SliceLayout p = patientSliceLayout(Mat3::identity(), PatientPlane(axis));
    const SliceLayout v = voxelSliceLayout(axis);
    CHECK(std::tie(p.sliceAxis, p.columnAxis, p.columnReversed, p.rowAxis, p.rowReversed) ==
          std::tie(v.sliceAxis, v.columnAxis, v.columnReversed, v.rowAxis, v.rowReversed));
  }
}

TEST_CASE("seg_dicom.nii.gz and its DICOM series give the same slice pictures in patient orientation") {
  if (!test::requireSharedData("seg_dicom.nii.gz and ct_dicom")) return;
  DatasetFiles files;
  files.volumePath = test::sharedData("totalsegmentator/ct_dicom").string();
  files.labelsPath = test::sharedData("totalsegmentator/seg_dicom.nii.gz").string();
  auto dataset = openDatasetFiles(files);  // labels resampled onto the DICOM grid through both affines
  REQUIRE_MESSAGE(dataset, (dataset ? "" : dataset.error().message));
  auto raw = loadImageFile(files.labelsPath);
  REQUIRE(raw);
  auto nifti = toLabelMap(*raw, files.labelsPath);  // the NIfTI's own (LAS) voxel order
  REQUIRE(nifti);
  const Geometry& gd = dataset->labels.geometry;
  const Geometry& gn = nifti->geometry;
  REQUIRE(gd.orientationCode() != gn.orientationCode());
  // Label values as grey (window 0…128) so renderSlice draws the two label maps as pictures.
  const auto asVolume = [](const LabelMap& labels) {
    Volume v(labels.geometry);
    for (std::size_t n = 0; n < v.voxels.size(); ++n) v.voxels[n] = std::int16_t(labels.voxels[n]);
    return v;
  };
  const Volume vd = asVolume(dataset->labels), vn = asVolume(*nifti);
  const Vec3 through = gd.indexToPatient({300, 260, 12});  // inside the body, off every centre
  for (int plane = 0; plane < 3; ++plane) {
    CAPTURE(plane);
    const auto request = [&](const Geometry& g, std::optional<SliceLayout> layout, int voxelAxis) {
      SliceRequest r;
      r.layout = layout;
      r.axis = voxelAxis;
      const int across = layout ? layout->sliceAxis : voxelAxis;
      r.index = int(std::lround(g.patientToIndex(through)[std::size_t(across)]));
      r.windowCentreHu = 64;
      r.windowWidthHu = 128;
      return r;
    };
    const SliceRequest rd = request(gd, patientSliceLayout(gd.direction, PatientPlane(plane)), 0);
    const SliceRequest rn = request(gn, patientSliceLayout(gn.direction, PatientPlane(plane)), 0);
    auto imageD = renderSlice(vd, nullptr, {}, rd);
    auto imageN = renderSlice(vn, nullptr, {}, rn);
    REQUIRE(imageD);
    REQUIRE(imageN);
    REQUIRE(imageD->width == imageN->width);
    REQUIRE(imageD->height == imageN->height);
    std::size_t same = 0, labelled = 0;
    double worstMm = 0;
    for (int y = 0; y < imageD->height; ++y)
      for (int x = 0; x < imageD->width; ++x) {
        const bool any = imageD->pixel(x, y)[0] > 0 || imageN->pixel(x, y)[0] > 0;
        labelled += any;
        same += any && imageD->pixel(x, y)[0] == imageN->pixel(x, y)[0];
        if ((x % 37) == 0 && (y % 5) == 0) worstMm = std::max(worstMm, norm(pointAt(gd, rd, x, y) - pointAt(gn, rn, x, y)));
      }
    MESSAGE(std::string(planeName(PatientPlane(plane))) << ": " << same << " of " << labelled << " labelled pixels equal; worst "
                                          << worstMm << " mm between the points shown");
    REQUIRE(labelled > 500);
    CHECK(double(same) / double(labelled) >= 0.99);
    CHECK(worstMm < 0.5);  // the same patient point at every pixel
    // Raw voxel order (what the axial pane showed before) puts different anatomy at the same pixel:
    // the NIfTI's axial picture was upside down against the DICOM one.
    if (plane == 2) {
      auto rawD = renderSlice(vd, nullptr, {}, request(gd, std::nullopt, rd.layout->sliceAxis));
      auto rawN = renderSlice(vn, nullptr, {}, request(gn, std::nullopt, rn.layout->sliceAxis));
      REQUIRE(rawD);
      REQUIRE(rawN);
      std::size_t rawSame = 0, rawLabelled = 0;
      for (int y = 0; y < rawD->height; ++y)
        for (int x = 0; x < rawD->width; ++x) {
          const bool any = rawD->pixel(x, y)[0] > 0 || rawN->pixel(x, y)[0] > 0;
          rawLabelled += any;
          rawSame += any && rawD->pixel(x, y)[0] == rawN->pixel(x, y)[0];
        }
      CHECK(double(rawSame) / double(rawLabelled) < 0.8);
    }
  }
}
