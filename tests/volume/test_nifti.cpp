// NIfTI loading (real TotalSegmentator files and hand-made headers) and writer round trips.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "io_test_files.h"
#include "test_support.h"
#include "volume/image_file.h"
#include "volume/nifti_io.h"

using namespace at;
using namespace at::test;

TEST_CASE("ct_small.nii.gz loads as 122x101x30 int16 HU on a 3 mm grid in RAS orientation") {
  if (!requireSharedData("ct_small.nii.gz")) return;
  const std::string path = sharedData("totalsegmentator/ct_small.nii.gz").string();
  auto loaded = loadNifti(path);
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  const Geometry& g = loaded->image.geometry;
  CHECK(g.dims == Dims{122, 101, 30});
  CHECK((loaded->storedKind == ScalarKind::Int16));
  for (int a = 0; a < 3; ++a) CHECK(g.spacingMm[std::size_t(a)] == doctest::Approx(3.0));
  // sform is diag(3,3,3) in RAS: i runs to patient right, j anterior, k superior.
  CHECK(g.orientationCode() == "RAS");
  CHECK(g.originMm[0] == doctest::Approx(177.956).epsilon(1e-4));
  CHECK(g.originMm[1] == doctest::Approx(-11.319).epsilon(1e-4));
  CHECK(g.originMm[2] == doctest::Approx(94.302).epsilon(1e-4));

  auto hu = toHuVolume(*loaded, path);
  REQUIRE_MESSAGE(hu, hu.error().message);
  const auto [lo, hi] = std::minmax_element(hu->voxels.begin(), hu->voxels.end());
  CHECK(*lo >= -1100);   // air, at most slightly below −1000
  CHECK(*lo <= -900);
  CHECK(*hi >= 700);     // bone present
  CHECK(*hi <= 3000);
}

TEST_CASE("seg_small.nii.gz holds 41 labels on the CT grid and its liver voxels are soft tissue") {
  if (!requireSharedData("seg_small.nii.gz")) return;
  const std::string ctPath = sharedData("totalsegmentator/ct_small.nii.gz").string();
  const std::string segPath = sharedData("totalsegmentator/seg_small.nii.gz").string();
  auto ct = loadNifti(ctPath);
  auto seg = loadNifti(segPath);
  REQUIRE(ct);
  REQUIRE_MESSAGE(seg, seg.error().message);
  CHECK((seg->storedKind == ScalarKind::UInt8));
  CHECK(seg->image.geometry.sameGridAs(ct->image.geometry));
  auto labels = toLabelMap(*seg, segPath);
  REQUIRE(labels);
  std::set<std::uint16_t> distinct(labels->voxels.begin(), labels->voxels.end());
  distinct.erase(0);
  CHECK(distinct.size() == 41);
  // Liver is label 5 in labels.json; its mean HU must be that of soft tissue.
  double sum = 0;
  std::size_t count = 0;
  for (std::size_t n = 0; n < labels->voxels.size(); ++n)
    if (labels->voxels[n] == 5) {
      sum += ct->image.voxels[n];
      ++count;
    }
  REQUIRE(count > 1000);
  const double mean = sum / double(count);
  CHECK(mean > 0);
  CHECK(mean < 150);
}

TEST_CASE("seg_dicom.nii.gz reads its RAS affine as an LAS grid: rows and slices run as the README says") {
  if (!requireSharedData("seg_dicom.nii.gz")) return;
  const std::string path = sharedData("totalsegmentator/seg_dicom.nii.gz").string();
  auto loaded = loadNifti(path);
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  const Geometry& g = loaded->image.geometry;
  CHECK(g.dims == Dims{512, 512, 20});
  CHECK(maxAbsDifference(g.spacingMm, Vec3{0.9765625, 0.9765625, 2.0}) < 1e-6);
  // sform diag(−0.977, 0.977, 2) in RAS: i → patient left, j → anterior, k → superior.
  CHECK(g.orientationCode() == "LAS");
  CHECK(maxAbsDifference(g.originMm, Vec3{-249.51171875, 61.51171875, -804.5}) < 1e-4);
  auto labels = toLabelMap(*loaded, path);
  REQUIRE(labels);
  std::set<std::uint16_t> distinct(labels->voxels.begin(), labels->voxels.end());
  CHECK(distinct.size() == 32);  // 31 structures and background
}

TEST_CASE("a float image on a random oblique grid round-trips through .nii and .nii.gz") {
  std::mt19937_64 rng(freshSeed("nifti float round trip"));
  TempDir dir;
  for (const char* name : {"image.nii", "image.nii.gz"}) {
    FloatVolume image(randomObliqueGeometry(rng, {7, 5, 4}));
    std::normal_distribution<float> value(0, 1000);
    for (float& v : image.voxels) v = value(rng);
    const std::string path = (dir / name).string();
    auto written = writeNiftiFloat(path, image);
    REQUIRE_MESSAGE(written, written.error().message);
    auto loaded = loadNifti(path);
    REQUIRE_MESSAGE(loaded, loaded.error().message);
    const Geometry& g = loaded->image.geometry;
    CHECK((loaded->storedKind == ScalarKind::Float32));
    CHECK(g.dims == image.geometry.dims);
    // NIfTI-1 stores the sform in float32.
    CHECK(maxAbsDifference(g.direction, image.geometry.direction) < 1e-5);
    CHECK(maxAbsDifference(g.spacingMm, image.geometry.spacingMm) < 1e-5);
    CHECK(maxAbsDifference(g.originMm, image.geometry.originMm) < 1e-3);
    CHECK(g.sameGridAs(image.geometry, 1e-3));
    CHECK(loaded->image.voxels == image.voxels);
  }
}

TEST_CASE("labels round-trip through writeNiftiLabels as uint16, including values above 255") {
  std::mt19937_64 rng(freshSeed("nifti labels round trip"));
  TempDir dir;
  LabelMap labels(randomObliqueGeometry(rng, {6, 6, 3}));
  std::uniform_int_distribution<int> value(0, 65535);
  for (auto& v : labels.voxels) v = std::uint16_t(value(rng));
  labels.voxels[0] = 65535;
  const std::string path = (dir / "labels.nii.gz").string();
  REQUIRE(writeNiftiLabels(path, labels));
  auto loaded = loadNifti(path);
  REQUIRE(loaded);
  CHECK((loaded->storedKind == ScalarKind::UInt16));
  auto back = toLabelMap(*loaded, path);
  REQUIRE(back);
  CHECK(back->voxels == labels.voxels);
  CHECK(back->geometry.sameGridAs(labels.geometry, 1e-3));
}

TEST_CASE("the sform wins over the qform and NIfTI's RAS world becomes LPS") {
  TempDir dir;
  RawNifti raw;
  raw.dims[0] = 2;
  raw.dims[1] = 3;
  raw.dims[2] = 4;
  raw.data.assign(2 * 3 * 4 * 2, '\0');
  raw.qformCode = 1;  // identity qform with 1 mm pixdim: must be ignored
  raw.sformCode = 1;
  // i → 0.5 mm towards patient left (RAS −x), j → 2 mm anterior... as columns of the sform:
  const double sform[3][4] = {{-0.5, 0, 0, 10}, {0, 0, 1.5, -20}, {0, 2, 0, 30}};
  std::memcpy(raw.srow, sform, sizeof sform);
  const auto path = dir / "sform.nii";
  writeBytes(path, raw.bytes());
  auto loaded = loadNifti(path.string());
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  const Geometry& g = loaded->image.geometry;
  CHECK(g.spacingMm[0] == doctest::Approx(0.5));
  CHECK(g.spacingMm[1] == doctest::Approx(2.0));
  CHECK(g.spacingMm[2] == doctest::Approx(1.5));
  // LPS = (−x, −y, z) of RAS.
  CHECK(maxAbsDifference(g.originMm, Vec3{-10, 20, 30}) < 1e-6);
  CHECK(maxAbsDifference(g.direction.column(0), Vec3{1, 0, 0}) < 1e-6);   // left
  CHECK(maxAbsDifference(g.direction.column(1), Vec3{0, 0, 1}) < 1e-6);   // superior
  CHECK(maxAbsDifference(g.direction.column(2), Vec3{0, -1, 0}) < 1e-6);  // anterior
  const Vec3 corner = g.indexToPatient({1, 2, 3});
  CHECK(maxAbsDifference(corner, Vec3{-10 + 0.5, 20 - 4.5, 30 + 4}) < 1e-6);
}

TEST_CASE("a qform-only header (180 degrees about z, qfac -1) gives the matching LPS frame") {
  TempDir dir;
  RawNifti raw;
  raw.data.assign(8 * 2, '\0');
  raw.qformCode = 1;
  raw.quatern[0] = 0;
  raw.quatern[1] = 0;
  raw.quatern[2] = 1;  // (b,c,d) = (0,0,1): rotation by 180° about z → RAS x,y negated = LPS identity
  raw.qfac = -1;        // k flipped
  raw.pixdim[0] = 0.8;
  raw.pixdim[1] = 0.9;
  raw.pixdim[2] = 2.5;
  raw.qoffset[0] = 5;
  raw.qoffset[1] = 6;
  raw.qoffset[2] = 7;
  writeBytes(dir / "q.nii", raw.bytes());
  auto loaded = loadNifti((dir / "q.nii").string());
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  const Geometry& g = loaded->image.geometry;
  CHECK(maxAbsDifference(g.spacingMm, Vec3{0.8, 0.9, 2.5}) < 1e-6);
  CHECK(g.orientationCode() == "LPI");
  CHECK(maxAbsDifference(g.originMm, Vec3{-5, -6, 7}) < 1e-6);
}

TEST_CASE("every supported NIfTI datatype loads with scl_slope and scl_inter applied, NIfTI-1 and NIfTI-2") {
  struct Case {
    std::int16_t datatype, bitpix;
    ScalarKind kind;
  };
  const Case cases[] = {{256, 8, ScalarKind::Int8},     {2, 8, ScalarKind::UInt8},
                        {4, 16, ScalarKind::Int16},     {512, 16, ScalarKind::UInt16},
                        {8, 32, ScalarKind::Int32},     {768, 32, ScalarKind::UInt32},
                        {16, 32, ScalarKind::Float32},  {64, 64, ScalarKind::Float64}};
  TempDir dir;
  for (int version : {1, 2})
    for (const Case& c : cases) {
      CAPTURE(version);
      CAPTURE(toString(c.kind));
      RawNifti raw;
      raw.version = version;
      raw.datatype = c.datatype;
      raw.bitpix = c.bitpix;
      raw.slope = 2;
      raw.inter = -3;
      const int stored[8] = {0, 1, 2, 3, 4, 5, 6, 100};
      const std::size_t width = std::size_t(c.bitpix / 8);
      raw.data.assign(8 * width, '\0');
      for (std::size_t n = 0; n < 8; ++n) {
        switch (c.kind) {
          case ScalarKind::Float32: putValue<float>(raw.data, n * width, float(stored[n])); break;
          case ScalarKind::Float64: putValue<double>(raw.data, n * width, double(stored[n])); break;
          default: std::memcpy(raw.data.data() + n * width, &stored[n], width); break;  // little endian
        }
      }
      std::string name = "t";
      name += std::to_string(version);
      name += toString(c.kind);
      name += ".nii";
      const auto path = dir / name;
      writeBytes(path, raw.bytes());
      auto loaded = loadNifti(path.string());
      REQUIRE_MESSAGE(loaded, loaded.error().message);
      CHECK((loaded->storedKind == c.kind));
      for (std::size_t n = 0; n < 8; ++n) CHECK(loaded->image.voxels[n] == float(stored[n] * 2 - 3));
    }
}

TEST_CASE("a degenerate sform falls back to a valid qform, with a note") {
  TempDir dir;
  RawNifti raw;
  raw.data.assign(16, '\0');
  raw.sformCode = 1;
  raw.srow[0][0] = raw.srow[1][1] = raw.srow[2][2] = 0;  // all-zero sform
  raw.qformCode = 1;
  raw.pixdim[0] = 2;
  raw.pixdim[1] = 3;
  raw.pixdim[2] = 4;
  writeBytes(dir / "fallback.nii", raw.bytes());
  auto loaded = loadNifti((dir / "fallback.nii").string());
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  CHECK(maxAbsDifference(loaded->image.geometry.spacingMm, Vec3{2, 3, 4}) < 1e-9);
  CHECK(loaded->image.geometry.orientationCode() == "RAS");
  bool noted = false;
  for (const auto& note : loaded->notes) noted |= note.find("sform unusable") != std::string::npos;
  CHECK(noted);
}
