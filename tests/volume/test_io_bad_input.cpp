// Broken inputs: every case is a one-line error that names the file and the problem, never a crash.
// Each test makes its own broken file in a TempDir (a valid file, then corrupted; or a header by hand).
#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "io_test_files.h"
#include "test_support.h"
#include "volume/image_file.h"
#include "volume/nifti_io.h"
#include "volume/nrrd_io.h"

using namespace at;
using namespace at::test;

namespace {

FloatVolume smallImage() {
  Geometry g;
  g.dims = {16, 12, 8};
  g.spacingMm = {0.7, 0.8, 2.0};
  FloatVolume image(g);
  for (std::size_t n = 0; n < image.voxels.size(); ++n) image.voxels[n] = float(int(n * 37 % 2001) - 1000);
  return image;
}

std::string validNifti(const TempDir& dir, const std::string& name) {
  const std::string path = (dir / name).string();
  REQUIRE(writeNiftiFloat(path, smallImage()));
  return path;
}

std::string validNrrd(const TempDir& dir, const std::string& name) {
  const std::string path = (dir / name).string();
  REQUIRE(writeNrrd(path, smallImage(), ScalarKind::Int16));
  return path;
}

std::string nrrdHeader(const std::string& replaceKey = "", const std::string& replaceValue = "") {
  const std::pair<const char*, const char*> fields[] = {{"type", "short"},          {"dimension", "3"},
                                                        {"sizes", "2 2 2"},         {"spacings", "1 1 1"},
                                                        {"endian", "little"},       {"encoding", "raw"}};
  std::string header = "NRRD0004\n";
  for (const auto& [key, value] : fields) {
    if (replaceKey == key && replaceValue.empty()) continue;
    header += std::string(key) + ": " + (replaceKey == key ? replaceValue : std::string(value)) + "\n";
  }
  if (!replaceValue.empty() && header.find(replaceKey + ":") == std::string::npos)
    header += replaceKey + ": " + replaceValue + "\n";
  return header + "\n";
}

const std::string kEightShorts(16, '\1');

}  // namespace

TEST_CASE("NIfTI: a truncated .nii says how many bytes the dimensions need and the file holds") {
  TempDir dir;
  const std::string path = validNifti(dir, "ct.nii");
  const std::string bytes = readBytes(path);
  writeBytes(path, bytes.substr(0, bytes.size() - 100));
  checkError(loadNifti(path), path, "dimensions 16x12x8 × float32 need 6144 bytes but the file holds 6044");
  writeBytes(path, bytes.substr(0, 200));
  checkError(loadNifti(path), path, "too short for a NIfTI header");
}

TEST_CASE("NIfTI: extra bytes after the voxel data are a size mismatch") {
  TempDir dir;
  const std::string path = validNifti(dir, "ct.nii");
  writeBytes(path, readBytes(path) + std::string(10, '\0'));
  checkError(loadNifti(path), path, "holds more data");
}

TEST_CASE("NIfTI: a truncated or garbled .nii.gz is an error naming the file") {
  TempDir dir;
  const std::string path = validNifti(dir, "ct.nii.gz");
  const std::string bytes = readBytes(path);
  writeBytes(path, bytes.substr(0, bytes.size() / 2));
  auto truncated = loadNifti(path);
  REQUIRE_FALSE(truncated);
  CHECK(truncated.error().message.rfind(path, 0) == 0);
  CHECK(truncated.error().message.find('\n') == std::string::npos);

  std::string garbled = bytes;
  for (std::size_t n = 20; n < garbled.size() - 20; n += 7) garbled[n] = char(garbled[n] ^ 0x5a);
  writeBytes(path, garbled);
  auto bad = loadNifti(path);
  REQUIRE_FALSE(bad);
  CAPTURE(bad.error().message);
  CHECK(bad.error().message.rfind(path, 0) == 0);
  CHECK((bad.error().message.find("corrupt") != std::string::npos ||
         bad.error().message.find("not a NIfTI") != std::string::npos));
}

TEST_CASE("NIfTI: wrong magic, not a NIfTI file at all, or a missing file") {
  TempDir dir;
  const std::string path = validNifti(dir, "ct.nii");
  std::string bytes = readBytes(path);
  std::memcpy(bytes.data() + 344, "ni1\0", 4);
  writeBytes(path, bytes);
  checkError(loadNifti(path), path, "magic");
  writeBytes(path, std::string(400, 'x'));
  checkError(loadNifti(path), path, "not a NIfTI file");
  const std::string missing = (dir / "absent.nii.gz").string();
  checkError(loadNifti(missing), missing, "no such file");
}

TEST_CASE("NIfTI: zero or negative spacing, unsupported datatypes and 4D images are refused") {
  TempDir dir;
  RawNifti raw;
  raw.data.assign(16, '\0');
  raw.qformCode = 1;
  raw.pixdim[1] = 0;
  const std::string zero = (dir / "zero.nii").string();
  writeBytes(zero, raw.bytes());
  checkError(loadNifti(zero), zero, "spacing must be positive");

  raw.pixdim[1] = -2;
  const std::string negative = (dir / "negative.nii").string();
  writeBytes(negative, raw.bytes());
  checkError(loadNifti(negative), negative, "spacing must be positive");

  RawNifti sform;
  sform.data.assign(16, '\0');
  sform.sformCode = 1;
  sform.srow[1][1] = 0;
  const std::string flat = (dir / "flat.nii").string();
  writeBytes(flat, sform.bytes());
  checkError(loadNifti(flat), flat, "zero spacing");

  RawNifti complex;
  complex.datatype = 32;  // DT_COMPLEX64
  complex.bitpix = 64;
  complex.data.assign(64, '\0');
  const std::string cplx = (dir / "complex.nii").string();
  writeBytes(cplx, complex.bytes());
  checkError(loadNifti(cplx), cplx, "unsupported NIfTI datatype");

  RawNifti fourD;
  fourD.extraDim4 = 3;
  fourD.data.assign(48, '\0');
  const std::string timeSeries = (dir / "4d.nii").string();
  writeBytes(timeSeries, fourD.bytes());
  checkError(loadNifti(timeSeries), timeSeries, "only 3D images");
}

TEST_CASE("NIfTI: dimensions × type larger than the data is refused before reading") {
  TempDir dir;
  RawNifti raw;
  raw.dims[0] = 4;
  raw.dims[1] = 4;
  raw.dims[2] = 4;
  raw.data.assign(10, '\0');
  const std::string path = (dir / "short.nii").string();
  writeBytes(path, raw.bytes());
  checkError(loadNifti(path), path, "dimensions 4x4x4 × int16 need 128 bytes but the file holds 10");
}

TEST_CASE("NIfTI and NRRD: images over the memory limit are refused before allocating") {
  TempDir dir;
  const std::string nii = validNifti(dir, "ct.nii.gz");
  ImageLoadOptions tight;
  tight.maxBytes = 1000;
  // 1536 voxels: 4 bytes as float, 2 for the HU copy, and the 6144-byte read piece of float32 data.
  checkError(loadNifti(nii, tight), nii,
             "needs 15360 bytes (float voxels, their HU or label copy and read buffers) but only 1000 bytes may be "
             "used (memory limit: the limit this load was given)");
  const std::string nrrd = validNrrd(dir, "ct.nrrd");
  checkError(loadNrrd(nrrd, tight), nrrd, "memory limit");

  // A header claiming 30000³ voxels with no data: refused by the machine's own limit.
  RawNifti huge;
  huge.dims[0] = huge.dims[1] = huge.dims[2] = 30000;
  const std::string hugePath = (dir / "huge.nii").string();
  writeBytes(hugePath, huge.bytes());
  checkError(loadNifti(hugePath), hugePath, "memory limit");
  const std::string hugeNrrd = (dir / "huge.nrrd").string();
  writeBytes(hugeNrrd, nrrdHeader("sizes", "30000 30000 30000"));
  checkError(loadNrrd(hugeNrrd), hugeNrrd, "memory limit");
  CHECK(availableImageBytes() > 0);
}

TEST_CASE("NRRD: wrong magic, unknown type and unknown encoding") {
  TempDir dir;
  const std::string path = (dir / "bad.nrrd").string();
  writeBytes(path, "NRRX0004\ntype: short\n\n");
  checkError(loadNrrd(path), path, "not a NRRD file");
  writeBytes(path, "");
  checkError(loadNrrd(path), path, "not a NRRD file");
  writeBytes(path, nrrdHeader("type", "complex") + kEightShorts);
  checkError(loadNrrd(path), path, "unsupported NRRD type 'complex'");
  writeBytes(path, nrrdHeader("encoding", "bzip2") + kEightShorts);
  checkError(loadNrrd(path), path, "unsupported NRRD encoding 'bzip2'");
  writeBytes(path, nrrdHeader("type") + kEightShorts);
  checkError(loadNrrd(path), path, "no 'type' field");
  writeBytes(path, nrrdHeader("sizes", "2 2") + kEightShorts);
  checkError(loadNrrd(path), path, "'sizes' lists 2 values but dimension is 3");
  writeBytes(path, nrrdHeader("dimension", "5") + kEightShorts);
  checkError(loadNrrd(path), path, "dimension 5 is not supported");
  writeBytes(path, nrrdHeader("space", "scanner-xyz-time") + kEightShorts);
  checkError(loadNrrd(path), path, "unsupported NRRD space");
  writeBytes(path, "NRRD0004\ntype short\n\n" + kEightShorts);
  checkError(loadNrrd(path), path, "line 2 is not a \"field: value\" line");
}

TEST_CASE("NRRD: dimensions × type ≠ data size, raw and gzip") {
  TempDir dir;
  const std::string path = (dir / "size.nrrd").string();
  writeBytes(path, nrrdHeader() + kEightShorts.substr(0, 10));
  checkError(loadNrrd(path), path, "dimensions 2x2x2 × int16 need 16 bytes but the data holds 10");
  writeBytes(path, nrrdHeader() + kEightShorts + "xx");
  checkError(loadNrrd(path), path, "need 16 bytes but the data holds 18");

  const std::string gz = validNrrd(dir, "ct.nrrd");
  std::string bytes = readBytes(gz);
  // Declared sizes smaller than the compressed content.
  std::string smaller = bytes;
  smaller.replace(smaller.find("sizes: 16 12 8"), 14, "sizes: 16 12 7");
  writeBytes(gz, smaller);
  checkError(loadNrrd(gz), gz, "decompressed data holds more");
}

TEST_CASE("NRRD: truncated and garbled gzip data") {
  TempDir dir;
  const std::string path = validNrrd(dir, "ct.nrrd");
  const std::string bytes = readBytes(path);
  writeBytes(path, bytes.substr(0, bytes.size() - 200));
  checkError(loadNrrd(path), path, "truncated");
  std::string garbled = bytes;
  const std::size_t dataStart = garbled.find("\n\n") + 2;
  for (std::size_t n = dataStart + 12; n < garbled.size() - 12; n += 5) garbled[n] = char(garbled[n] ^ 0xa5);
  writeBytes(path, garbled);
  checkError(loadNrrd(path), path, "corrupt");
}

TEST_CASE("NRRD: zero or negative spacing and degenerate directions") {
  TempDir dir;
  const std::string path = (dir / "spacing.nrrd").string();
  writeBytes(path, nrrdHeader("spacings", "1 0 1") + kEightShorts);
  checkError(loadNrrd(path), path, "spacing 0 of axis 1 is not positive");
  writeBytes(path, nrrdHeader("spacings", "1 1 -2") + kEightShorts);
  checkError(loadNrrd(path), path, "spacing -2 of axis 2 is not positive");
  writeBytes(path, "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nspace: LPS\n"
                   "space directions: (1,0,0) (0,0,0) (0,0,1)\nendian: little\nencoding: raw\n\n" + kEightShorts);
  checkError(loadNrrd(path), path, "axis 1 has zero spacing");
  writeBytes(path, "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nspace: LPS\n"
                   "space directions: (1,0,0) (2,0,0) (0,0,1)\nendian: little\nencoding: raw\n\n" + kEightShorts);
  checkError(loadNrrd(path), path, "parallel");
  writeBytes(path, "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nspace: LPS\n"
                   "space directions: (1,0,0) (0,1) (0,0,1)\nendian: little\nencoding: raw\n\n" + kEightShorts);
  checkError(loadNrrd(path), path, "no valid vector for axis 1");
}

TEST_CASE("NRRD: missing detached data files are named") {
  TempDir dir;
  const std::string single = (dir / "single.nhdr").string();
  writeBytes(single, "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\n"
                     "data file: absent.raw\n");
  checkError(loadNrrd(single), single, "absent.raw: no such file");

  const std::string multi = (dir / "multi.nhdr").string();
  writeBytes(dir / "slice.1", std::string(8, '\0'));
  writeBytes(multi, "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\n"
                    "data file: slice.%d 1 2 1\n");
  checkError(loadNrrd(multi), multi, "slice.2: no such file");

  const std::string noData = (dir / "nodata.nhdr").string();
  writeBytes(noData, "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\n");
  checkError(loadNrrd(noData), noData, "names no data file and holds no data");

  const std::string badFormat = (dir / "format.nhdr").string();
  writeBytes(badFormat, "NRRD0004\ntype: short\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\n"
                        "data file: slice.%s 1 2 1\n");
  checkError(loadNrrd(badFormat), badFormat, "must hold exactly one %d conversion");

  const std::string missing = (dir / "absent.nrrd").string();
  checkError(loadNrrd(missing), missing, "no such file");
}

TEST_CASE("NRRD: a 4D segmentation with several layers is refused with a clear reason") {
  TempDir dir;
  const std::string path = (dir / "layers.seg.nrrd").string();
  writeBytes(path, "NRRD0004\ntype: uchar\ndimension: 4\nsizes: 3 2 2 2\n"
                   "space directions: none (1,0,0) (0,1,0) (0,0,1)\nencoding: raw\n\n" + std::string(24, '\0'));
  checkError(loadNrrd(path), path, "holds 3 layers");
}

TEST_CASE("toHuVolume refuses NaN, infinity and values outside int16, naming the voxel") {
  TempDir dir;
  const std::string path = (dir / "float.nii.gz").string();
  struct Case {
    float value;
    const char* expect;
  };
  const Case cases[] = {{std::numeric_limits<float>::quiet_NaN(), "voxel (3,2,1) is NaN"},
                        {std::numeric_limits<float>::infinity(), "voxel (3,2,1) is +inf"},
                        {40000.0f, "voxel (3,2,1) is 40000, outside the int16 range"},
                        {-40000.0f, "outside the int16 range"}};
  for (const Case& c : cases) {
    FloatVolume image = smallImage();
    image.at(3, 2, 1) = c.value;
    REQUIRE(writeNiftiFloat(path, image));
    auto loaded = loadNifti(path);
    REQUIRE_MESSAGE(loaded, loaded.error().message);  // loaders keep values; conversion decides
    checkError(toHuVolume(*loaded, path), path, c.expect);
  }
  auto fine = loadNifti(validNifti(dir, "fine.nii"));
  REQUIRE(fine);
  auto hu = toHuVolume(*fine, "fine.nii");
  REQUIRE(hu);
  CHECK(hu->at(5, 4, 3) == std::int16_t(fine->image.at(5, 4, 3)));
}

TEST_CASE("toLabelMap refuses negative, fractional and too large label values, naming the voxel") {
  LoadedImage loaded;
  loaded.image = smallImage();
  for (float& v : loaded.image.voxels) v = std::abs(v);
  struct Case {
    float value;
    const char* expect;
  };
  const Case cases[] = {{-1.0f, "label voxel (0,1,2) is -1, negative"},
                        {2.5f, "is 2.5, not an integer"},
                        {70000.0f, "is 70000, above 65535"},
                        {std::numeric_limits<float>::quiet_NaN(), "is NaN, not a finite number"}};
  for (const Case& c : cases) {
    LoadedImage broken = loaded;
    broken.image.at(0, 1, 2) = c.value;
    checkError(toLabelMap(broken, "labels.nrrd"), "labels.nrrd", c.expect);
  }
  auto labels = toLabelMap(loaded, "labels.nrrd");
  REQUIRE(labels);
  CHECK(labels->at(7, 3, 2) == std::uint16_t(loaded.image.at(7, 3, 2)));
}

TEST_CASE("randomly corrupted NIfTI and NRRD files load or fail with a one-line error, never crash") {
  std::mt19937_64 rng(freshSeed("loader corruption fuzz"));
  TempDir dir;
  const std::string nrrdRaw = (dir / "raw.nrrd").string();
  writeBytes(nrrdRaw, "NRRD0004\ntype: short\ndimension: 3\nsizes: 4 3 2\nspace: left-posterior-superior\n"
                      "space directions: (1,0,0) (0,1,0) (0,0,2.5)\nendian: little\nencoding: raw\n"
                      "space origin: (1,2,3)\nSegment0_Name:=a\nSegment0_LabelValue:=1\n\n" + std::string(48, '\2'));
  const std::string sources[] = {validNifti(dir, "base.nii"), validNifti(dir, "base.nii.gz"),
                                 validNrrd(dir, "base.nrrd"), nrrdRaw};
  const char* digits = "0123456789-. ():%x\n";
  int failures = 0, loads = 0;
  for (const std::string& source : sources) {
    const std::string original = readBytes(source);
    const bool nrrd = source.find(".nrrd") != std::string::npos;
    const std::size_t headerEnd = nrrd ? original.find("\n\n") + 2 : (source.find(".gz") != std::string::npos ? original.size() : 352);
    const std::string target = (dir / ("fuzz" + source.substr(source.find('.')))).string();
    for (int round = 0; round < 150; ++round) {
      std::string bytes = original;
      std::uniform_int_distribution<int> mutations(1, 6);
      const int count = mutations(rng);
      for (int m = 0; m < count; ++m) {
        std::uniform_int_distribution<std::size_t> where(0, headerEnd - 1);
        const std::size_t at = where(rng);
        if (nrrd)
          bytes[at] = digits[std::uniform_int_distribution<int>(0, int(std::strlen(digits)) - 1)(rng)];
        else
          bytes[at] = char(std::uniform_int_distribution<int>(0, 255)(rng));
      }
      if (round % 10 == 0) bytes.resize(std::uniform_int_distribution<std::size_t>(0, bytes.size())(rng));
      writeBytes(target, bytes);
      ImageLoadOptions options;
      options.maxBytes = std::size_t(64) << 20;
      auto loaded = nrrd ? loadNrrd(target, options) : loadNifti(target, options);
      if (loaded) {
        ++loads;
        CHECK(loaded->image.voxels.size() == loaded->image.geometry.dims.count());
        continue;
      }
      ++failures;
      CHECK(loaded.error().message.rfind(target, 0) == 0);
      CHECK(loaded.error().message.find('\n') == std::string::npos);
    }
  }
  MESSAGE("corrupted files: " << failures << " refused, " << loads << " still loaded");
  CHECK(failures > 0);
}
