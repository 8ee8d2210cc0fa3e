// DICOM series on the real files in ../shared/data: the JPEG 2000 abdominal CT and the head CT.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <map>
#include <numeric>
#include <random>

#include <dcmtk/dcmdata/dcpixel.h>
#include <dcmtk/dcmdata/dcpixseq.h>
#include <dcmtk/dcmdata/dcpxitem.h>
#include <dcmtk/dcmdata/dcrleerg.h>
#include <dcmtk/dcmjpeg/djencode.h>
#include <dcmtk/dcmjpeg/djrplol.h>
#include <dcmtk/dcmjpls/djencode.h>
#include <dcmtk/dcmjpls/djrparam.h>

#include "dicom_test_files.h"
#include "test_support.h"
#include "volume/dicom_series.h"
#include "volume/image_file.h"
#include "volume/nrrd_io.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

double fractionIn(const FloatVolume& v, float lo, float hi) {
  const auto n = std::count_if(v.voxels.begin(), v.voxels.end(), [&](float x) { return x >= lo && x <= hi; });
  return double(n) / double(v.voxels.size());
}

// The JPEG 2000 series, loaded once for the tests that only read it (decoding takes about a second).
const Result<LoadedImage>& ctDicom() {
  static const Result<LoadedImage> loaded = loadDicomSeries(test::sharedData("totalsegmentator/ct_dicom").string());
  return loaded;
}

}  // namespace

TEST_CASE("DICOM series: the JPEG 2000 CT loads as 512x512x20 with spacing from PixelSpacing and positions") {
  if (!test::requireSharedData("DICOM series (ct_dicom)")) return;
  const fs::path folder = test::sharedData("totalsegmentator/ct_dicom");
  const auto& loaded = ctDicom();
  REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().message));
  const Geometry& g = loaded->image.geometry;
  CHECK(g.dims == Dims{512, 512, 20});

  const fs::path anyFile = fs::directory_iterator(folder)->path();
  const double rowSpacing = test::dicomNumber(anyFile, DCM_PixelSpacing, 0);
  const double columnSpacing = test::dicomNumber(anyFile, DCM_PixelSpacing, 1);
  CHECK(g.spacingMm[0] == doctest::Approx(columnSpacing).epsilon(1e-6));
  CHECK(g.spacingMm[1] == doctest::Approx(rowSpacing).epsilon(1e-6));
  CHECK(std::abs(g.spacingMm[0] - 0.977) < 1e-3);
  CHECK(std::abs(g.spacingMm[1] - 0.977) < 1e-3);
  // 2 mm between positions although SliceThickness says 3 mm.
  CHECK(test::dicomNumber(anyFile, DCM_SliceThickness) == doctest::Approx(3.0));
  CHECK(g.spacingMm[2] == doctest::Approx(2.0).epsilon(1e-6));
  CHECK((loaded->storedKind == ScalarKind::UInt16));

  // Rows along +x (patient left), columns along +y (posterior), slices sorted along the normal +z.
  CHECK(g.orientationCode() == "LPS");
  CHECK(g.originMm[2] == doctest::Approx(-804.5));
  CHECK(g.indexToPatient({0, 0, 19})[2] == doctest::Approx(-766.5));
}

TEST_CASE("DICOM series: every decoded JPEG 2000 slice spans exactly its file's stored pixel range in HU") {
  // Each file states its Smallest/LargestImagePixelValue: an independent check of the JPEG 2000
  // decoding, the rescale (intercept −1024) and the sorting by position.
  if (!test::requireSharedData("DICOM series (ct_dicom)")) return;
  const fs::path folder = test::sharedData("totalsegmentator/ct_dicom");
  const auto& loaded = ctDicom();
  REQUIRE(loaded);
  const Geometry& g = loaded->image.geometry;
  const std::size_t sliceVoxels = std::size_t(g.dims.x) * g.dims.y;
  int checked = 0;
  for (const auto& entry : fs::directory_iterator(folder)) {
    const double z = test::dicomNumber(entry.path(), DCM_ImagePositionPatient, 2);
    const int k = int(std::lround(g.patientToIndex({g.originMm[0], g.originMm[1], z})[2]));
    REQUIRE(k >= 0);
    REQUIRE(k < g.dims.z);
    const double intercept = test::dicomNumber(entry.path(), DCM_RescaleIntercept);
    const double smallest = test::dicomNumber(entry.path(), DCM_SmallestImagePixelValue) + intercept;
    const double largest = test::dicomNumber(entry.path(), DCM_LargestImagePixelValue) + intercept;
    auto first = loaded->image.voxels.begin() + std::ptrdiff_t(k * sliceVoxels);
    auto [lo, hi] = std::minmax_element(first, first + std::ptrdiff_t(sliceVoxels));
    CHECK(*lo == doctest::Approx(smallest));
    CHECK(*hi == doctest::Approx(largest));
    ++checked;
  }
  CHECK(checked == 20);
}

TEST_CASE("DICOM series: the abdominal CT holds plausible Hounsfield units") {
  if (!test::requireSharedData("DICOM series (ct_dicom)")) return;
  const auto& loaded = ctDicom();
  REQUIRE(loaded);
  const FloatVolume& v = loaded->image;
  const double air = fractionIn(v, -1100, -900);   // outside the body, lungs, bowel gas
  const double soft = fractionIn(v, -100, 150);    // fat, muscle, organs
  const double bone = fractionIn(v, 300, 3000);    // vertebrae, ribs
  MESSAGE("air " << air << ", soft tissue " << soft << ", bone " << bone);
  CHECK(air > 0.2);
  CHECK(soft > 0.2);
  CHECK(bone > 0.002);
  CHECK(bone < 0.1);
  auto [lo, hi] = std::minmax_element(v.voxels.begin(), v.voxels.end());
  CHECK(*lo >= -1024.0f);
  CHECK(*hi < 3100.0f);
}

TEST_CASE("DICOM series: the head CT folder loads 93 slices and ignores its licence file") {
  if (!test::requireSharedData("DICOM series (headsq)")) return;
  auto loaded = loadDicomSeries(test::sharedData("headsq/dicom").string());
  REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().message));
  const Geometry& g = loaded->image.geometry;
  CHECK(g.dims == Dims{64, 64, 93});
  CHECK(g.spacingMm[0] == doctest::Approx(3.2));
  CHECK(g.spacingMm[1] == doctest::Approx(3.2));
  CHECK(g.spacingMm[2] == doctest::Approx(1.5));
  CHECK((loaded->storedKind == ScalarKind::Int16));
  REQUIRE(!loaded->notes.empty());
  CHECK(loaded->notes.front().find("93 slices") != std::string::npos);
}

TEST_CASE("DICOM series: head CT slices equal the raw VTK slice files, in reverse order") {
  // headsq/nrrd/quarter.N holds raw little-endian int16 slices. CTHead1.dcm (ImagePositionPatient
  // z = 0) carries the pixels of quarter.93: the DICOM k axis runs opposite to the file numbering.
  if (!test::requireSharedData("DICOM series (headsq)")) return;
  auto loaded = loadDicomSeries(test::sharedData("headsq/dicom").string());
  REQUIRE(loaded);
  const std::size_t sliceVoxels = 64 * 64;
  std::size_t mismatches = 0;
  for (int k = 0; k < 93; ++k) {
    std::ifstream raw(test::sharedData("headsq/nrrd/quarter." + std::to_string(93 - k)), std::ios::binary);
    std::vector<std::int16_t> slice(sliceVoxels);
    REQUIRE(raw.read(reinterpret_cast<char*>(slice.data()), std::streamsize(sliceVoxels * 2)));
    for (std::size_t p = 0; p < sliceVoxels; ++p)
      if (loaded->image.voxels[k * sliceVoxels + p] != float(slice[p])) ++mismatches;
  }
  CHECK(mismatches == 0);
}

TEST_CASE("DICOM series: headsq DICOM and NRRD give the same volume on the same voxel grid size") {
  // The NRRD (space: 3D-left-handed, no origin) numbers its slices from the other end: NRRD slice
  // k is DICOM slice 92 − k (quarter.1 is the top DICOM slice), which is what makes its index frame
  // left-handed. Values, spacing and in-plane axes agree; the NRRD carries no patient position, so
  // only the DICOM grid is anchored in LPS and origins are not compared.
  if (!test::requireSharedData("headsq DICOM vs NRRD")) return;
  auto dicom = loadDicomSeries(test::sharedData("headsq/dicom").string());
  auto nrrd = loadNrrd(test::sharedData("headsq/nrrd/quarter.nhdr").string());
  REQUIRE_MESSAGE(dicom, (dicom ? "" : dicom.error().message));
  REQUIRE_MESSAGE(nrrd, (nrrd ? "" : nrrd.error().message));
  const Geometry& gd = dicom->image.geometry;
  const Geometry& gn = nrrd->image.geometry;
  REQUIRE(gn.dims == gd.dims);
  for (int a = 0; a < 3; ++a) CHECK(gn.spacingMm[a] == doctest::Approx(gd.spacingMm[a]));
  CHECK((nrrd->storedKind == dicom->storedKind));
  // In-plane axes agree; the slice axes point opposite ways (3D-left-handed read as L, P, inferior).
  for (int r = 0; r < 3; ++r) {
    CHECK(gn.direction.m[r][0] == doctest::Approx(gd.direction.m[r][0]));
    CHECK(gn.direction.m[r][1] == doctest::Approx(gd.direction.m[r][1]));
    CHECK(gn.direction.m[r][2] == doctest::Approx(-gd.direction.m[r][2]));
  }
  std::size_t mismatches = 0;
  for (int k = 0; k < gd.dims.z; ++k)
    for (int j = 0; j < gd.dims.y; ++j)
      for (int i = 0; i < gd.dims.x; ++i)
        if (dicom->image.at(i, j, k) != nrrd->image.at(i, j, gd.dims.z - 1 - k)) ++mismatches;
  CHECK(mismatches == 0);
}

TEST_CASE("DICOM series: loadImageFile on a folder, on one file of the series, and on bad paths") {
  if (!test::requireSharedData("DICOM series (headsq)")) return;
  const fs::path folder = test::sharedData("headsq/dicom");
  auto fromFolder = loadImageFile(folder.string());
  auto fromFile = loadImageFile((folder / "CTHead40.dcm").string());
  REQUIRE(fromFolder);
  REQUIRE_MESSAGE(fromFile, (fromFile ? "" : fromFile.error().message));
  CHECK(fromFile->image.geometry.sameGridAs(fromFolder->image.geometry));
  CHECK(fromFile->image.voxels == fromFolder->image.voxels);
  CHECK(fromFile->notes.back().find("CTHead40.dcm") != std::string::npos);

  auto missing = loadImageFile((folder / "no-such-file.dcm").string());
  REQUIRE(!missing);
  CHECK(missing.error().message.find("no such file") != std::string::npos);

  auto licence = loadImageFile((folder / "Slicer_License_head.txt").string());
  REQUIRE(!licence);
  CHECK(licence.error().message.find("unrecognised format") != std::string::npos);
  CHECK(licence.error().message.find("Slicer_License_head.txt") != std::string::npos);
}

TEST_CASE("DICOM files: looksLikeDicomFile tells DICOM from other files") {
  if (!test::requireSharedData("DICOM preamble")) return;
  CHECK(looksLikeDicomFile(test::sharedData("headsq/dicom/CTHead1.dcm").string()));
  CHECK(looksLikeDicomFile(test::sharedData("dcmqi/liver.dcm").string()));
  CHECK_FALSE(looksLikeDicomFile(test::sharedData("headsq/dicom/Slicer_License_head.txt").string()));
  CHECK_FALSE(looksLikeDicomFile(test::sharedData("headsq/nrrd/quarter.nhdr").string()));
  CHECK_FALSE(looksLikeDicomFile(test::sharedData("headsq/nrrd/no-such-file").string()));
}

TEST_CASE("DICOM series: a randomly rotated and renamed copy of the head slices loads with the rotated geometry") {
  // Property: rotating ImageOrientationPatient and every ImagePositionPatient by one rotation R and
  // shuffling the file names leaves the voxels unchanged and turns the direction matrix into R.
  if (!test::requireSharedData("DICOM series (oblique)")) return;
  std::mt19937_64 rng(test::freshSeed("DICOM oblique series"));
  std::normal_distribution<double> gauss;
  // A uniformly random rotation from a random unit quaternion.
  double q[4];
  double length = 0;
  for (double& c : q) {
    c = gauss(rng);
    length += c * c;
  }
  for (double& c : q) c /= std::sqrt(length);
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  Mat3 rotation;
  rotation.m = {{{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                 {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                 {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}}};

  const int slices = 12;
  std::vector<int> names(slices);
  std::iota(names.begin(), names.end(), 0);
  std::shuffle(names.begin(), names.end(), rng);
  test::TempDir dir("at-dicom-oblique");
  for (int n = 1; n <= slices; ++n) {
    const std::string source = "CTHead" + std::to_string(n) + ".dcm";
    const std::string target = std::to_string(names[n - 1]) + "_slice.dcm";
    REQUIRE(test::rewriteDicom(test::sharedData("headsq/dicom/" + source), dir / target,
                               [&](DcmDataset& d) {
                                 const auto p = test::positionOf(d);
                                 const Vec3 r = rotation * Vec3{p[0], p[1], p[2]};
                                 test::setPosition(d, {r[0], r[1], r[2]});
                                 const Vec3 row = rotation.column(0), column = rotation.column(1);
                                 std::string iop;
                                 for (double v : {row[0], row[1], row[2], column[0], column[1], column[2]}) {
                                   if (!iop.empty()) iop.push_back('\\');
                                   iop.append(std::to_string(v));
                                 }
                                 d.putAndInsertString(DCM_ImageOrientationPatient, iop.c_str());
                               }));
  }
  auto rotated = loadDicomSeries(dir.path().string());
  REQUIRE_MESSAGE(rotated, (rotated ? "" : rotated.error().message));
  auto straight = loadDicomSeries(test::sharedData("headsq/dicom").string());
  REQUIRE(straight);
  const Geometry& g = rotated->image.geometry;
  REQUIRE(g.dims == Dims{64, 64, slices});
  CHECK(g.spacingMm[2] == doctest::Approx(1.5).epsilon(1e-4));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) CHECK(g.direction.m[r][c] == doctest::Approx(rotation.m[r][c]).epsilon(1e-5));
  for (int a = 0; a < 3; ++a) CHECK(g.originMm[a] == doctest::Approx(0).epsilon(1e-4));
  const std::size_t count = std::size_t(64) * 64 * slices;
  CHECK(std::equal(rotated->image.voxels.begin(), rotated->image.voxels.end(), straight->image.voxels.begin()));
  CHECK(rotated->image.voxels.size() == count);
}

namespace {

// DCMTK's encoders, registered for the lifetime of the test program (tests make compressed inputs).
struct EncoderRegistration {
  EncoderRegistration() {
    DJEncoderRegistration::registerCodecs();
    DJLSEncoderRegistration::registerCodecs();
    DcmRLEEncoderRegistration::registerCodecs();
  }
  ~EncoderRegistration() {
    DcmRLEEncoderRegistration::cleanup();
    DJLSEncoderRegistration::cleanup();
    DJEncoderRegistration::cleanup();
  }
};

}  // namespace

TEST_CASE("DICOM series: RLE, JPEG-LS and lossless JPEG copies of the head slices decode to the same HU") {
  if (!test::requireSharedData("DICOM codecs")) return;
  static EncoderRegistration encoders;
  auto reference = loadDicomSeries(test::sharedData("headsq/dicom").string());
  REQUIRE(reference);
  const int slices = 8;
  const std::size_t count = std::size_t(64) * 64 * slices;
  DJ_RPLossless jpegLossless;  // process 14, first-order prediction
  DJLSRepresentationParameter jpegLsLossless(0, OFTrue);
  const struct {
    const char* name;
    E_TransferSyntax syntax;
    const DcmRepresentationParameter* parameter;
  } codecs[] = {{"RLE", EXS_RLELossless, nullptr},
                {"JPEG-LS", EXS_JPEGLSLossless, &jpegLsLossless},
                {"JPEG lossless", EXS_JPEGProcess14SV1, &jpegLossless}};
  for (const auto& codec : codecs) {
    INFO(std::string(codec.name));
    test::TempDir dir("at-dicom-codec");
    for (int n = 1; n <= slices; ++n) {
      DcmFileFormat file;
      const std::string name = "CTHead" + std::to_string(n) + ".dcm";
      REQUIRE(file.loadFile(OFFilename(test::sharedData("headsq/dicom/" + name).c_str())).good());
      REQUIRE(file.getDataset()->chooseRepresentation(codec.syntax, codec.parameter).good());
      REQUIRE(file.getDataset()->canWriteXfer(codec.syntax));
      REQUIRE(file.saveFile(OFFilename((dir / name).c_str()), codec.syntax).good());
    }
    REQUIRE(test::dicomTransferSyntax(dir / "CTHead1.dcm") == codec.syntax);
    auto decoded = loadDicomSeries(dir.path().string());
    REQUIRE_MESSAGE(decoded, (decoded ? "" : decoded.error().message));
    REQUIRE(decoded->image.voxels.size() == count);
    CHECK(std::equal(decoded->image.voxels.begin(), decoded->image.voxels.end(), reference->image.voxels.begin()));
  }
}

namespace {

void putBox(std::vector<std::uint8_t>& out, const char* type, const std::vector<std::uint8_t>& payload) {
  const std::uint32_t size = std::uint32_t(8 + payload.size());
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(std::uint8_t(size >> shift));
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), payload.begin(), payload.end());
}

// Wraps a raw J2K codestream into a minimal JP2 file (signature, ftyp, jp2h with ihdr + colr,
// jp2c), of even length as DICOM fragments must be.
std::vector<std::uint8_t> wrapInJp2(const std::vector<std::uint8_t>& codestream, std::uint32_t width,
                                    std::uint32_t height, int bitsPerSample, bool isSigned) {
  auto be32 = [](std::vector<std::uint8_t>& v, std::uint32_t x) {
    for (int shift = 24; shift >= 0; shift -= 8) v.push_back(std::uint8_t(x >> shift));
  };
  std::vector<std::uint8_t> out = {0, 0, 0, 0x0C, 'j', 'P', ' ', ' ', 0x0D, 0x0A, 0x87, 0x0A};
  putBox(out, "ftyp", {'j', 'p', '2', ' ', 0, 0, 0, 0, 'j', 'p', '2', ' '});
  std::vector<std::uint8_t> ihdr;
  be32(ihdr, height);
  be32(ihdr, width);
  ihdr.insert(ihdr.end(), {0, 1, std::uint8_t((bitsPerSample - 1) | (isSigned ? 0x80 : 0)), 7, 0, 0});
  std::vector<std::uint8_t> header;
  putBox(header, "ihdr", ihdr);
  putBox(header, "colr", {1, 0, 0, 0, 0, 0, 17});  // enumerated colour space: greyscale
  putBox(out, "jp2h", header);
  if ((out.size() + 8 + codestream.size()) % 2) putBox(out, "xml ", {' '});
  putBox(out, "jp2c", codestream);
  return out;
}

}  // namespace

TEST_CASE("DICOM series: JPEG 2000 frames wrapped in JP2 boxes decode like raw codestreams") {
  if (!test::requireSharedData("DICOM JP2")) return;
  const fs::path source = test::sharedData("totalsegmentator/ct_dicom");
  const auto& reference = ctDicom();
  REQUIRE(reference);
  test::TempDir dir("at-dicom-jp2");
  int rewritten = 0;
  for (const auto& entry : fs::directory_iterator(source)) {
    const bool wrap = rewritten < 5;  // a series mixing both forms
    if (!wrap) {
      fs::copy_file(entry.path(), dir / entry.path().filename());
      continue;
    }
    REQUIRE(test::rewriteDicom(entry.path(), dir / entry.path().filename(), [&](DcmDataset& d) {
      DcmElement* element = nullptr;
      REQUIRE(d.findAndGetElement(DCM_PixelData, element).good());
      auto* pixelData = static_cast<DcmPixelData*>(element);
      DcmPixelSequence* fragments = nullptr;
      REQUIRE(pixelData->getEncapsulatedRepresentation(d.getOriginalXfer(), nullptr, fragments).good());
      std::vector<std::uint8_t> codestream;
      for (unsigned long i = 1; i < fragments->card(); ++i) {
        DcmPixelItem* item = nullptr;
        Uint8* bytes = nullptr;
        REQUIRE(fragments->getItem(item, i).good());
        REQUIRE(item->getUint8Array(bytes).good());
        codestream.insert(codestream.end(), bytes, bytes + item->getLength());
      }
      const std::vector<std::uint8_t> jp2 = wrapInJp2(codestream, 512, 512, 12, false);
      auto* sequence = new DcmPixelSequence(DCM_PixelSequenceTag);
      sequence->insert(new DcmPixelItem(DCM_PixelItemTag));  // empty basic offset table
      auto* frame = new DcmPixelItem(DCM_PixelItemTag);
      frame->putUint8Array(jp2.data(), Uint32(jp2.size()));
      sequence->insert(frame);
      pixelData->putOriginalRepresentation(d.getOriginalXfer(), nullptr, sequence);
    }));
    ++rewritten;
  }
  REQUIRE(rewritten == 5);
  auto decoded = loadDicomSeries(dir.path().string());
  REQUIRE_MESSAGE(decoded, (decoded ? "" : decoded.error().message));
  CHECK(decoded->image.voxels == reference->image.voxels);
}
