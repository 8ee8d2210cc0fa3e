// Broken DICOM series, made in a TempDir from the real headsq / ct-3slice / ct_dicom files with
// DCMTK: each gives a one-line error naming the folder and the problem, never a crash.
#include <doctest/doctest.h>

#include <algorithm>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "dicom_test_files.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/dicom_seg.h"
#include "volume/dicom_series.h"
#include "volume/image_file.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

constexpr int kSlices = 10;

// Copies CTHead1..CTHead10 (z = 0 … 13.5 mm, 1.5 mm apart) into `folder`, letting `edit` change
// slice n (1-based) on the way.
void writeHeadSlices(const fs::path& folder, const std::function<void(int, DcmDataset&)>& edit) {
  fs::create_directories(folder);
  for (int n = 1; n <= kSlices; ++n) {
    const std::string name = "CTHead" + std::to_string(n) + ".dcm";
    REQUIRE(test::rewriteDicom(test::sharedData("headsq/dicom/" + name), folder / name,
                               [&](DcmDataset& d) { edit(n, d); }));
  }
}

// Loads `folder`, expects an error that is one line, starts with the folder and contains `what`.
std::string expectSeriesError(const fs::path& folder, const std::string& what) {
  auto loaded = loadDicomSeries(folder.string());
  REQUIRE_MESSAGE(!loaded, "expected an error mentioning '" << what << "'");
  const std::string& message = loaded.error().message;
  INFO(message);
  CHECK(message.find('\n') == std::string::npos);
  CHECK(message.rfind(folder.string() + ": ", 0) == 0);
  CHECK_MESSAGE(message.find(what) != std::string::npos, message);
  return message;
}

void shiftZ(DcmDataset& d, double dz) {
  auto p = test::positionOf(d);
  p[2] += dz;
  test::setPosition(d, p);
}

}  // namespace

TEST_CASE("DICOM bad input: an intact copy of the head slices loads (the reference for the broken ones)") {
  if (!test::requireSharedData("DICOM bad input")) return;
  test::TempDir dir("at-dicom-bad");
  writeHeadSlices(dir / "ok", [](int, DcmDataset&) {});
  auto loaded = loadDicomSeries((dir / "ok").string());
  REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().message));
  CHECK(loaded->image.geometry.dims == Dims{64, 64, kSlices});
  CHECK(loaded->image.geometry.spacingMm[2] == doctest::Approx(1.5));
}

TEST_CASE("DICOM bad input: uneven slice spacing is refused and the distinct spacings are reported") {
  if (!test::requireSharedData("DICOM bad input")) return;
  test::TempDir dir("at-dicom-bad");
  // Slices 6… move 0.5 mm up: one gap of 2 mm among gaps of 1.5 mm.
  writeHeadSlices(dir / "uneven", [](int n, DcmDataset& d) {
    if (n >= 6) shiftZ(d, 0.5);
  });
  const std::string message = expectSeriesError(dir / "uneven", "uneven slice spacing");
  CHECK(message.find("1.5, 2 mm") != std::string::npos);
}

TEST_CASE("DICOM bad input: a missing slice (a gap of twice the spacing) is refused") {
  if (!test::requireSharedData("DICOM bad input")) return;
  test::TempDir dir("at-dicom-bad");
  writeHeadSlices(dir / "gap", [](int n, DcmDataset& d) {
    if (n >= 6) shiftZ(d, 1.5);
  });
  const std::string message = expectSeriesError(dir / "gap", "missing slices");
  CHECK(message.find("gap of 3 mm") != std::string::npos);
  CHECK(message.find("CTHead5.dcm and CTHead6.dcm") != std::string::npos);
}

TEST_CASE("DICOM bad input: gantry tilt (positions not advancing along the slice normal) is refused") {
  if (!test::requireSharedData("DICOM bad input")) return;
  test::TempDir dir("at-dicom-bad");
  // Each slice 0.3 mm further posterior: an 11° tilt.
  writeHeadSlices(dir / "tilt", [](int n, DcmDataset& d) {
    auto p = test::positionOf(d);
    p[1] += 0.3 * (n - 1);
    test::setPosition(d, p);
  });
  expectSeriesError(dir / "tilt", "gantry tilt");
}

TEST_CASE("DICOM bad input: non-orthogonal ImageOrientationPatient is refused") {
  if (!test::requireSharedData("DICOM bad input")) return;
  test::TempDir dir("at-dicom-bad");
  writeHeadSlices(dir / "shear", [](int, DcmDataset& d) {
    d.putAndInsertString(DCM_ImageOrientationPatient, "1\\0\\0\\0.2\\0.9797959\\0");
  });
  expectSeriesError(dir / "shear", "not orthogonal");
}

TEST_CASE("DICOM bad input: slices of different sizes in one series are refused") {
  if (!test::requireSharedData("DICOM bad input")) return;
  test::TempDir dir("at-dicom-bad");
  writeHeadSlices(dir / "mixed", [](int n, DcmDataset& d) {
    if (n == 4) {
      d.putAndInsertUint16(DCM_Rows, 32);
      d.putAndInsertUint16(DCM_Columns, 128);
    }
  });
  const std::string message = expectSeriesError(dir / "mixed", "mixed slice sizes");
  CHECK(message.find("64x64") != std::string::npos);
  CHECK(message.find("128x32 (CTHead4.dcm)") != std::string::npos);
}

TEST_CASE("DICOM bad input: two slices at one position, a missing position and a multi-frame image") {
  if (!test::requireSharedData("DICOM bad input")) return;
  test::TempDir dir("at-dicom-bad");
  writeHeadSlices(dir / "duplicate", [](int n, DcmDataset& d) {
    if (n == 3) test::setPosition(d, {0, 0, 1.5});
  });
  expectSeriesError(dir / "duplicate", "same slice position");

  writeHeadSlices(dir / "noposition", [](int n, DcmDataset& d) {
    if (n == 7) delete d.remove(DCM_ImagePositionPatient);
  });
  expectSeriesError(dir / "noposition", "CTHead7.dcm: missing ImagePositionPatient");

  writeHeadSlices(dir / "multiframe", [](int n, DcmDataset& d) {
    if (n == 2) d.putAndInsertString(DCM_NumberOfFrames, "2");
  });
  expectSeriesError(dir / "multiframe", "multi-frame images are not supported");
}

TEST_CASE("DICOM bad input: a truncated file is reported by name") {
  if (!test::requireSharedData("DICOM bad input")) return;
  test::TempDir dir("at-dicom-bad");
  writeHeadSlices(dir / "truncated", [](int, DcmDataset&) {});
  for (const std::size_t keep : {std::size_t(200), std::size_t(6000)}) {  // in the header; in the pixels
    const fs::path victim = dir / "truncated" / "CTHead5.dcm";
    writeHeadSlices(dir / "truncated", [](int, DcmDataset&) {});
    fs::resize_file(victim, keep);
    expectSeriesError(dir / "truncated", "CTHead5.dcm");
  }
}

TEST_CASE("DICOM bad input: a truncated JPEG 2000 slice is reported by name") {
  if (!test::requireSharedData("DICOM bad input")) return;
  test::TempDir dir("at-dicom-bad");
  const fs::path folder = dir / "j2k";
  fs::create_directory(folder);
  fs::path victim;
  for (const auto& entry : fs::directory_iterator(test::sharedData("totalsegmentator/ct_dicom"))) {
    fs::copy_file(entry.path(), folder / entry.path().filename());
    victim = folder / entry.path().filename();
  }
  fs::resize_file(victim, fs::file_size(victim) - 60000);
  expectSeriesError(folder, victim.filename().string());
}

TEST_CASE("DICOM bad input: an unsupported transfer syntax is named") {
  if (!test::requireSharedData("DICOM bad input")) return;
  test::TempDir dir("at-dicom-bad");
  const fs::path folder = dir / "xfer";
  fs::create_directory(folder);
  // JPEG 2000 Part 2 multi-component (…4.92) has the same length as …4.90 and no decoder here.
  const fs::path source = fs::directory_iterator(test::sharedData("totalsegmentator/ct_dicom"))->path();
  std::ifstream in(source, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string from = "1.2.840.10008.1.2.4.90", to = "1.2.840.10008.1.2.4.92";
  const std::size_t at = bytes.find(from);
  REQUIRE(at != std::string::npos);
  bytes.replace(at, from.size(), to);
  std::ofstream(folder / "slice.dcm", std::ios::binary) << bytes;
  expectSeriesError(folder, "unsupported transfer syntax");
}

TEST_CASE("DICOM bad input: empty folders, folders without DICOM files, and missing folders") {
  test::TempDir dir("at-dicom-bad");
  fs::create_directory(dir / "empty");
  expectSeriesError(dir / "empty", "no DICOM files");

  fs::create_directory(dir / "text");
  std::ofstream(dir / "text" / "README.txt") << "not DICOM\n";
  std::ofstream(dir / "text" / "not_dicom.dcm") << std::string(200, 'x');
  expectSeriesError(dir / "text", "no DICOM files");

  expectSeriesError(dir / "absent", "no such folder");

  auto viaDispatch = loadImageFile((dir / "absent").string());
  REQUIRE(!viaDispatch);
  CHECK(viaDispatch.error().message.find("no such file or folder") != std::string::npos);
  std::ofstream(dir / "volume.xyz") << "?";
  auto unknown = loadImageFile((dir / "volume.xyz").string());
  REQUIRE(!unknown);
  CHECK(unknown.error().message ==
        (dir / "volume.xyz").string() + ": unrecognised format (expected a DICOM folder, .nii, .nii.gz, .nrrd, .nhdr or .inv3)");
  auto notSeg = loadDicomSeg((dir / "volume.xyz").string());
  REQUIRE(!notSeg);
  CHECK(notSeg.error().message.find("volume.xyz") != std::string::npos);
}

TEST_CASE("DICOM bad input: a folder with two series loads the largest and says which, or the one asked for") {
  if (!test::requireSharedData("DICOM two series")) return;
  test::TempDir dir("at-dicom-two");
  const fs::path folder = dir / "two";
  writeHeadSlices(folder, [](int, DcmDataset&) {});
  for (const auto& entry : fs::directory_iterator(test::sharedData("dcmqi/ct-3slice")))
    fs::copy_file(entry.path(), folder / ("ct3_" + entry.path().filename().string()));
  const std::string headUid = test::dicomString(folder / "CTHead1.dcm", DCM_SeriesInstanceUID);
  const std::string ctUid = test::dicomString(folder / "ct3_01.dcm", DCM_SeriesInstanceUID);
  REQUIRE(headUid != ctUid);

  auto largest = loadDicomSeries(folder.string());
  REQUIRE_MESSAGE(largest, (largest ? "" : largest.error().message));
  CHECK(largest->image.geometry.dims == Dims{64, 64, kSlices});
  REQUIRE(!largest->notes.empty());
  const std::string& note = largest->notes.front();
  INFO(note);
  CHECK(note.find(headUid) != std::string::npos);
  CHECK(note.find("10 slices") != std::string::npos);
  CHECK(note.find("skipped 1 other series (3 files)") != std::string::npos);

  ImageLoadOptions options;
  options.dicomSeriesUid = ctUid;
  auto chosen = loadDicomSeries(folder.string(), options);
  REQUIRE_MESSAGE(chosen, (chosen ? "" : chosen.error().message));
  CHECK(chosen->image.geometry.dims == Dims{512, 512, 3});
  CHECK(chosen->notes.front().find(ctUid) != std::string::npos);

  options.dicomSeriesUid = "1.2.3.4.5";
  auto unknown = loadDicomSeries(folder.string(), options);
  REQUIRE(!unknown);
  CHECK(unknown.error().message.find("no series with SeriesInstanceUID 1.2.3.4.5") != std::string::npos);
  CHECK(unknown.error().message.find(headUid + " (10)") != std::string::npos);

  // One file of the smaller series, given as a path, loads that series.
  auto viaFile = loadImageFile((folder / "ct3_02.dcm").string());
  REQUIRE_MESSAGE(viaFile, (viaFile ? "" : viaFile.error().message));
  CHECK(viaFile->image.geometry.dims == Dims{512, 512, 3});
}

TEST_CASE("DICOM bad input: a broken dataset's volume error reaches openDatasetFiles unchanged") {
  if (!test::requireSharedData("DICOM bad input")) return;
  test::TempDir dir("at-dicom-bad");
  writeHeadSlices(dir / "gap", [](int n, DcmDataset& d) {
    if (n >= 6) shiftZ(d, 1.5);
  });
  DatasetFiles files;
  files.volumePath = (dir / "gap").string();
  auto dataset = openDatasetFiles(files);
  REQUIRE(!dataset);
  CHECK(dataset.error().message.rfind(files.volumePath + ": missing slices", 0) == 0);
}

TEST_CASE("DICOM bad input: a truncated DICOM SEG is reported by name") {
  if (!test::requireSharedData("DICOM SEG bad input")) return;
  test::TempDir dir("at-dicom-bad");
  const fs::path seg = dir / "liver.dcm";
  for (const std::uintmax_t keep : {std::uintmax_t(300), std::uintmax_t(3000), std::uintmax_t(60000)}) {
    fs::copy_file(test::sharedData("dcmqi/liver.dcm"), seg, fs::copy_options::overwrite_existing);
    fs::resize_file(seg, keep);
    auto loaded = loadImageFile(seg.string());
    REQUIRE(!loaded);
    INFO(loaded.error().message);
    CHECK(loaded.error().message.rfind(seg.string() + ": ", 0) == 0);
    CHECK(loaded.error().message.find('\n') == std::string::npos);
  }
}

TEST_CASE("DICOM bad input: a series larger than the memory limit is refused before decoding") {
  if (!test::requireSharedData("DICOM memory limit")) return;
  ImageLoadOptions options;
  options.maxBytes = 64 * 64 * 4 * 10;  // ten slices of the 93
  const std::string folder = test::sharedData("headsq/dicom").string();
  auto loaded = loadDicomSeries(folder, options);
  REQUIRE(!loaded);
  INFO(loaded.error().message);
  CHECK(loaded.error().message.rfind(folder + ": ", 0) == 0);
  CHECK(loaded.error().message.find("64x64x93") != std::string::npos);
  CHECK(loaded.error().message.find("memory limit") != std::string::npos);
  // The float voxels, their HU copy, and per decoding thread (8 at most) a slice's buffers.
  options.maxBytes = 64 * 64 * 93 * 6 + 8 * (64 * 64 * 12 + 16384);
  CHECK(loadDicomSeries(folder, options));
}

TEST_CASE("DICOM bad input: a SEG whose frames lie kilometres apart is refused, not allocated") {
  if (!test::requireSharedData("DICOM SEG memory limit")) return;
  test::TempDir dir("at-dicom-bad");
  const fs::path seg = dir / "spread.dcm";
  int frame = 0;
  // Frame 3 moves 10 km up: 1 mm slices would need 512×512×10⁷ voxels.
  REQUIRE(test::rewriteDicom(test::sharedData("dcmqi/liver.dcm"), seg, [&](DcmDataset& d) {
    test::editFramePositions(d, [&](std::array<double, 3> p) {
      if (++frame == 3) p[2] += 1e7;
      return p;
    });
  }));
  auto loaded = loadDicomSeg(seg.string());
  REQUIRE(!loaded);
  INFO(loaded.error().message);
  CHECK(loaded.error().message.rfind(seg.string() + ": ", 0) == 0);
  CHECK(loaded.error().message.find("memory limit") != std::string::npos);
}

TEST_CASE("DICOM bad input: a SEG frame at an absurd position is refused") {
  if (!test::requireSharedData("DICOM SEG positions")) return;
  test::TempDir dir("at-dicom-bad");
  const fs::path seg = dir / "absurd.dcm";
  int frame = 0;
  REQUIRE(test::rewriteDicom(test::sharedData("dcmqi/liver.dcm"), seg, [&](DcmDataset& d) {
    test::editFramePositions(d, [&](std::array<double, 3> p) {
      if (++frame == 2) p[2] += 1e15;
      return p;
    });
  }));
  auto loaded = loadDicomSeg(seg.string());
  REQUIRE(!loaded);
  INFO(loaded.error().message);
  CHECK(loaded.error().message.rfind(seg.string() + ": ", 0) == 0);
  CHECK(loaded.error().message.find("implausibly many slices") != std::string::npos);
}

TEST_CASE("DICOM bad input: a JPEG 2000 frame whose size disagrees with Rows/Columns is refused") {
  if (!test::requireSharedData("DICOM JPEG 2000 size")) return;
  test::TempDir dir("at-dicom-bad");
  const fs::path folder = dir / "j2ksize";
  fs::create_directory(folder);
  const fs::path source = fs::directory_iterator(test::sharedData("totalsegmentator/ct_dicom"))->path();
  REQUIRE(test::rewriteDicom(source, folder / "slice.dcm", [](DcmDataset& d) { d.putAndInsertUint16(DCM_Columns, 256); }));
  const std::string message = expectSeriesError(folder, "JPEG 2000 image is 512x512 but the header says 256x512");
  CHECK(message.find("slice.dcm") != std::string::npos);
}

TEST_CASE("DICOM bad input: a SEG whose NumberOfFrames, BitsAllocated or PixelData disagree with its frames is refused") {
  if (!test::requireSharedData("DICOM SEG frame count")) return;
  test::TempDir dir("at-dicom-bad");
  const fs::path seg = dir / "frames.dcm";
  // liver.dcm: three 512×512 frames described by three per-frame functional groups.
  const std::vector<std::pair<std::string, std::function<void(DcmDataset&)>>> edits = {
      {"no NumberOfFrames", [](DcmDataset& d) { delete d.remove(DCM_NumberOfFrames); }},
      {"NumberOfFrames 0", [](DcmDataset& d) { d.putAndInsertString(DCM_NumberOfFrames, "0"); }},
      {"NumberOfFrames 1", [](DcmDataset& d) { d.putAndInsertString(DCM_NumberOfFrames, "1"); }},
      {"NumberOfFrames 2", [](DcmDataset& d) { d.putAndInsertString(DCM_NumberOfFrames, "2"); }},
      {"NumberOfFrames 4", [](DcmDataset& d) { d.putAndInsertString(DCM_NumberOfFrames, "4"); }},
      {"NumberOfFrames 100000", [](DcmDataset& d) { d.putAndInsertString(DCM_NumberOfFrames, "100000"); }},
      {"NumberOfFrames -3", [](DcmDataset& d) { d.putAndInsertString(DCM_NumberOfFrames, "-3"); }},
      {"BitsAllocated 8", [](DcmDataset& d) { d.putAndInsertUint16(DCM_BitsAllocated, 8); }},
      {"PixelData of 2 frames", [](DcmDataset& d) {
         std::vector<Uint8> bits(2 * 512 * 512 / 8, 0xff);
         d.putAndInsertUint8Array(DCM_PixelData, bits.data(), bits.size());
       }},
      {"no PixelData", [](DcmDataset& d) { delete d.remove(DCM_PixelData); }},
  };
  for (const auto& [what, edit] : edits) {
    INFO(what);
    REQUIRE(test::rewriteDicom(test::sharedData("dcmqi/liver.dcm"), seg, edit));
    const std::string before = test::readFile(seg);
    auto loaded = loadImageFile(seg.string());
    REQUIRE(!loaded);
    INFO(loaded.error().message);
    CHECK(loaded.error().message.rfind(seg.string() + ": ", 0) == 0);
    CHECK(loaded.error().message.find('\n') == std::string::npos);
    CHECK(test::readFile(seg) == before);
  }
}

TEST_CASE("DICOM SEG: binary frames that do not end on a byte boundary are read bit by bit in order") {
  if (!test::requireSharedData("DICOM SEG bit packing")) return;
  test::TempDir dir("at-dicom-bad");
  const fs::path seg = dir / "packed.dcm";
  // Three 3×3 frames = 27 bits: frame f (in file order) has f + 1 pixels set, so its bits cross
  // byte boundaries. Frame 1 sets pixel 4, frame 2 pixels 0 and 8, frame 3 pixels 1, 2 and 3.
  const std::vector<std::vector<int>> setPixels = {{4}, {0, 8}, {1, 2, 3}};
  std::vector<Uint8> bits(4, 0);
  for (std::size_t f = 0; f < setPixels.size(); ++f)
    for (int p : setPixels[f]) {
      const std::size_t bit = f * 9 + std::size_t(p);
      bits[bit / 8] |= Uint8(1u << (bit % 8));
    }
  REQUIRE(test::rewriteDicom(test::sharedData("dcmqi/liver.dcm"), seg, [&](DcmDataset& d) {
    d.putAndInsertUint16(DCM_Rows, 3);
    d.putAndInsertUint16(DCM_Columns, 3);
    d.putAndInsertUint8Array(DCM_PixelData, bits.data(), bits.size());
  }));
  auto loaded = loadDicomSeg(seg.string());
  REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().message));
  REQUIRE(loaded->image.geometry.dims.x == 3);
  REQUIRE(loaded->image.geometry.dims.y == 3);
  // Each frame lands on one slice; map a frame to its slice by the pixels it sets.
  std::vector<std::vector<int>> slicesSet;
  for (int k = 0; k < loaded->image.geometry.dims.z; ++k) {
    std::vector<int> set;
    for (int p = 0; p < 9; ++p)
      if (loaded->image.at(p % 3, p / 3, k) != 0) set.push_back(p);
    if (!set.empty()) slicesSet.push_back(set);
  }
  std::sort(slicesSet.begin(), slicesSet.end());
  std::vector<std::vector<int>> expected = setPixels;
  std::sort(expected.begin(), expected.end());
  CHECK(slicesSet == expected);
}
