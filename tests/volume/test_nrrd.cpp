// NRRD loading (the real headsq and dcmqi files, hand-written headers for every supported form)
// and writer round trips.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>

#include "io_test_files.h"
#include "test_support.h"
#include "volume/image_file.h"
#include "volume/nrrd_io.h"

using namespace at;
using namespace at::test;

namespace {

std::string int16Bytes(const std::vector<int>& values, bool bigEndian = false) {
  std::string out;
  for (int v : values) {
    const auto u = std::uint16_t(std::int16_t(v));
    const char lo = char(u & 0xff), hi = char(u >> 8);
    out += bigEndian ? std::string{hi, lo} : std::string{lo, hi};
  }
  return out;
}

std::vector<int> ramp(int n, int start = 0) {
  std::vector<int> v(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) v[std::size_t(i)] = start + i;
  return v;
}

std::vector<float> asFloats(const std::vector<int>& v) { return std::vector<float>(v.begin(), v.end()); }

// gzip bytes made through our own writer: write a NRRD, take the bytes after its header.
std::string gzipThroughWriter(const TempDir& dir, const std::vector<int>& int16Values) {
  Geometry g;
  g.dims = Dims{int(int16Values.size()), 1, 1};
  FloatVolume image(g);
  image.voxels = asFloats(int16Values);
  const auto path = dir / "gzip-source.nrrd";
  REQUIRE(writeNrrd(path.string(), image, ScalarKind::Int16));
  const std::string bytes = readBytes(path);
  return bytes.substr(bytes.find("\n\n") + 2);
}

}  // namespace

TEST_CASE("headsq quarter.nhdr reads 93 slice files as 64x64x93 int16 with 3.2x3.2x1.5 mm spacing") {
  if (!requireSharedData("headsq NRRD")) return;
  const auto path = sharedData("headsq/nrrd/quarter.nhdr");
  auto loaded = loadNrrd(path.string());
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  const Geometry& g = loaded->image.geometry;
  CHECK(g.dims == Dims{64, 64, 93});
  CHECK((loaded->storedKind == ScalarKind::Int16));
  CHECK(maxAbsDifference(g.spacingMm, Vec3{3.2, 3.2, 1.5}) < 1e-9);
  // space: 3D-left-handed is read as L, P, I: slice 1 is the top slice of the DICOM series.
  CHECK(g.orientationCode() == "LPI");
  // LPS is right-handed, so the file's left-handed index axes have a determinant of −1 in it.
  CHECK(g.direction.determinant() == doctest::Approx(-1.0));
  // Slice k comes from quarter.(k+1), little endian, i fastest.
  for (int k : {0, 46, 92}) {
    const std::string slice = readBytes(sharedData("headsq/nrrd/quarter." + std::to_string(k + 1)));
    REQUIRE(slice.size() == 64 * 64 * 2);
    for (int n : {0, 100, 2080, 4095}) {
      std::int16_t v;
      std::memcpy(&v, slice.data() + 2 * n, 2);
      CHECK(loaded->image.at(n % 64, n / 64, k) == float(v));
    }
  }
  const auto [lo, hi] = std::minmax_element(loaded->image.voxels.begin(), loaded->image.voxels.end());
  CHECK(*lo >= 0);
  CHECK(*hi > 1000);  // skull
}

TEST_CASE("dcmqi label-map NRRDs read as 512x512x3 LPS grids with their origin and few label values") {
  if (!requireSharedData("dcmqi NRRD")) return;
  for (const char* name : {"liver_seg.nrrd", "spine_seg.nrrd", "heart_seg.nrrd", "liver_spine_seg.nrrd",
                           "partial_overlaps-1.nrrd"}) {
    CAPTURE(name);
    const auto path = sharedData(std::string("dcmqi/") + name);
    auto loaded = loadNrrd(path.string());
    REQUIRE_MESSAGE(loaded, loaded.error().message);
    const Geometry& g = loaded->image.geometry;
    CHECK(g.dims == Dims{512, 512, 3});
    CHECK(g.orientationCode() == "LPS");
    CHECK(maxAbsDifference(g.spacingMm, Vec3{0.810547, 0.810547, 1.0}) < 1e-9);
    CHECK(maxAbsDifference(g.originMm, Vec3{-235.2, -226.8, -128.69}) < 1e-5);
    auto labels = toLabelMap(*loaded, path.string());
    REQUIRE(labels);
    std::set<std::uint16_t> distinct(labels->voxels.begin(), labels->voxels.end());
    CHECK(distinct.count(0) == 1);
    CHECK(distinct.size() >= 2);
    CHECK(distinct.size() <= 6);
  }
}

TEST_CASE("writeNrrd round-trips every scalar kind on a random oblique grid") {
  std::mt19937_64 rng(freshSeed("nrrd round trip"));
  TempDir dir;
  const ScalarKind kinds[] = {ScalarKind::Int8,  ScalarKind::UInt8,  ScalarKind::Int16,   ScalarKind::UInt16,
                              ScalarKind::Int32, ScalarKind::UInt32, ScalarKind::Float32, ScalarKind::Float64};
  for (ScalarKind kind : kinds) {
    CAPTURE(toString(kind));
    FloatVolume image(randomObliqueGeometry(rng, {5, 4, 3}));
    std::uniform_int_distribution<int> small(0, 120);
    for (float& v : image.voxels) v = float(small(rng));
    const auto path = dir / (std::string(toString(kind)) + ".nrrd");
    auto written = writeNrrd(path.string(), image, kind);
    REQUIRE_MESSAGE(written, written.error().message);
    auto loaded = loadNrrd(path.string());
    REQUIRE_MESSAGE(loaded, loaded.error().message);
    CHECK((loaded->storedKind == kind));
    CHECK(loaded->image.voxels == image.voxels);
    CHECK(maxAbsDifference(loaded->image.geometry.direction, image.geometry.direction) < 1e-12);
    CHECK(maxAbsDifference(loaded->image.geometry.spacingMm, image.geometry.spacingMm) < 1e-12);
    CHECK(maxAbsDifference(loaded->image.geometry.originMm, image.geometry.originMm) < 1e-12);
  }
}

TEST_CASE("a RAS-space header is converted to LPS") {
  TempDir dir;
  const std::string header =
      "NRRD0004\ntype: short\ndimension: 3\nspace: right-anterior-superior\nsizes: 2 2 2\n"
      "space directions: (0,2,0) (1.5,0,0) (0,0,-3)\nendian: little\nencoding: raw\n"
      "space origin: (10,20,30)\n\n";
  writeBytes(dir / "ras.nrrd", header + int16Bytes(ramp(8)));
  auto loaded = loadNrrd((dir / "ras.nrrd").string());
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  const Geometry& g = loaded->image.geometry;
  CHECK(maxAbsDifference(g.spacingMm, Vec3{2, 1.5, 3}) < 1e-12);
  CHECK(maxAbsDifference(g.originMm, Vec3{-10, -20, 30}) < 1e-12);
  CHECK(maxAbsDifference(g.direction.column(0), Vec3{0, -1, 0}) < 1e-12);  // anterior
  CHECK(maxAbsDifference(g.direction.column(1), Vec3{-1, 0, 0}) < 1e-12);  // right
  CHECK(maxAbsDifference(g.direction.column(2), Vec3{0, 0, -1}) < 1e-12);  // inferior
  CHECK(g.orientationCode() == "ARI");
  CHECK(loaded->image.voxels == asFloats(ramp(8)));
}

TEST_CASE("detached data: a single gzip file with byte skip, a LIST, and a %03d format counting down") {
  TempDir dir;
  const std::vector<int> values = ramp(24, -5);  // 4x3x2
  // Single gzip data file, 'byte skip' applies to the decompressed bytes.
  {
    std::vector<int> padded = {7, 7};  // 4 bytes of padding to skip
    padded.insert(padded.end(), values.begin(), values.end());
    writeBytes(dir / "single.raw.gz", gzipThroughWriter(dir, padded));
    writeBytes(dir / "single.nhdr",
               "NRRD0005\ntype: int16\ndimension: 3\nsizes: 4 3 2\nspacings: 1 1 2\nendian: little\n"
               "encoding: gzip\nbyte skip: 4\ndata file: single.raw.gz\n");
    auto loaded = loadNrrd((dir / "single.nhdr").string());
    REQUIRE_MESSAGE(loaded, loaded.error().message);
    CHECK(loaded->image.voxels == asFloats(values));
    CHECK(loaded->image.geometry.spacingMm[2] == 2.0);
  }
  // LIST: one file per slice, named in the header.
  {
    writeBytes(dir / "a.raw", int16Bytes({values.begin(), values.begin() + 12}));
    writeBytes(dir / "b.raw", int16Bytes({values.begin() + 12, values.end()}));
    writeBytes(dir / "list.nhdr",
               "NRRD0004\ntype: short\ndimension: 3\nsizes: 4 3 2\nendian: little\nencoding: raw\n"
               "data file: LIST 2\na.raw\nb.raw\n");
    auto loaded = loadNrrd((dir / "list.nhdr").string());
    REQUIRE_MESSAGE(loaded, loaded.error().message);
    CHECK(loaded->image.voxels == asFloats(values));
  }
  // Format with zero padding, counting down: slice 0 is s002, slice 1 is s001; big endian, line skip.
  {
    writeBytes(dir / "s002", "comment line\n" + int16Bytes({values.begin(), values.begin() + 12}, true));
    writeBytes(dir / "s001", "comment line\n" + int16Bytes({values.begin() + 12, values.end()}, true));
    writeBytes(dir / "format.nhdr",
               "NRRD0004\ntype: short\ndimension: 3\nsizes: 4 3 2\nendian: big\nencoding: raw\nline skip: 1\n"
               "data file: s%03d 2 1 -1 2\n");
    auto loaded = loadNrrd((dir / "format.nhdr").string());
    REQUIRE_MESSAGE(loaded, loaded.error().message);
    CHECK(loaded->image.voxels == asFloats(values));
  }
  // byte skip -1: the data are the last bytes of the file.
  {
    writeBytes(dir / "tail.raw", std::string(37, 'x') + int16Bytes(values));
    writeBytes(dir / "tail.nhdr",
               "NRRD0004\ntype: short\ndimension: 3\nsizes: 4 3 2\nendian: little\nencoding: raw\nbyte skip: -1\n"
               "data file: tail.raw\n");
    auto loaded = loadNrrd((dir / "tail.nhdr").string());
    REQUIRE_MESSAGE(loaded, loaded.error().message);
    CHECK(loaded->image.voxels == asFloats(values));
  }
}

TEST_CASE("a 3D Slicer .seg.nrrd with a leading size-1 axis gives its segments' names, values and colours") {
  TempDir dir;
  std::vector<int> labels(4 * 3 * 2, 0);
  labels[5] = 1;
  labels[17] = 3;
  const std::string header =
      "NRRD0004\ntype: unsigned char\ndimension: 4\nspace: left-posterior-superior\nsizes: 1 4 3 2\n"
      "space directions: none (0.5,0,0) (0,0.5,0) (0,0,1)\nkinds: list domain domain domain\n"
      "encoding: raw\nspace origin: (1,2,3)\n"
      "Segment0_Color:=0.9 0.1 0.2\nSegment0_ID:=Segment_1\nSegment0_LabelValue:=1\nSegment0_Layer:=0\n"
      "Segment0_Name:=liver\nSegment1_Color:=0.1 0.2 0.9\nSegment1_LabelValue:=3\nSegment1_Layer:=0\n"
      "Segment1_Name:=spleen\n\n";
  std::string data;
  for (int v : labels) data += char(v);
  writeBytes(dir / "test.seg.nrrd", header + data);
  auto loaded = loadNrrd((dir / "test.seg.nrrd").string());
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  CHECK(loaded->image.geometry.dims == Dims{4, 3, 2});
  CHECK(loaded->image.geometry.spacingMm[0] == 0.5);
  CHECK(maxAbsDifference(loaded->image.geometry.originMm, Vec3{1, 2, 3}) < 1e-12);
  CHECK(loaded->image.voxels == asFloats(labels));
  REQUIRE(loaded->segments.size() == 2);
  CHECK(loaded->segments[0].name == "liver");
  CHECK(loaded->segments[0].label == 1);
  CHECK(loaded->segments[0].colour[0] == doctest::Approx(0.9));
  CHECK(loaded->segments[1].name == "spleen");
  CHECK(loaded->segments[1].label == 3);
  CHECK(loaded->segments[1].colour[2] == doctest::Approx(0.9));
}
