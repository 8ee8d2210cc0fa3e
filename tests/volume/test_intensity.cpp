// The intensity model: CT in HU against plain intensities (µCT uint8/uint16, MR, fractional
// values), how they are stored in int16 and windowed, and the label-map test that must not take a
// uint8 µCT for a label map.
#include <doctest/doctest.h>

#include <cmath>
#include <filesystem>

#include "dicom_test_files.h"
#include "synthetic_scans.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/image_file.h"
#include "volume/intensity.h"
#include "volume/nifti_io.h"
#include "volume/nrrd_io.h"

using namespace at;

namespace fs = std::filesystem;

TEST_CASE("decideIntensity follows the documented order: forced choice, DICOM modality, storage and air") {
  IntensityEvidence ct;
  ct.modality = "CT";
  ct.rescaleGiven = true;
  ct.minValue = -1024;
  CHECK(decideIntensity(ct, IntensityChoice::Auto).first == IntensityUnit::Hounsfield);
  CHECK(decideIntensity(ct, IntensityChoice::Plain).first == IntensityUnit::Plain);
  IntensityEvidence ctNumbers = ct;  // CT numbers never rescaled: air at 0
  ctNumbers.minValue = 0;
  CHECK(decideIntensity(ctNumbers, IntensityChoice::Auto).first == IntensityUnit::Plain);
  CHECK(decideIntensity(ctNumbers, IntensityChoice::Hounsfield).first == IntensityUnit::Hounsfield);
  IntensityEvidence mr;
  mr.modality = "MR";
  mr.minValue = -2000;  // even with negative values an MR is not in HU
  CHECK(decideIntensity(mr, IntensityChoice::Auto).first == IntensityUnit::Plain);
  IntensityEvidence uct;
  uct.unsignedStorage = true;
  uct.maxValue = 255;
  CHECK(decideIntensity(uct, IntensityChoice::Auto).first == IntensityUnit::Plain);
  IntensityEvidence nifti;  // signed data without modality: HU when it reaches air
  nifti.minValue = -1024;
  CHECK(decideIntensity(nifti, IntensityChoice::Auto).first == IntensityUnit::Hounsfield);
  nifti.minValue = 0;
  CHECK(decideIntensity(nifti, IntensityChoice::Auto).first == IntensityUnit::Plain);
  CHECK(!parseIntensityChoice("Houns"));
  CHECK(*parseIntensityChoice("hu") == IntensityChoice::Hounsfield);
}

TEST_CASE("A uint8 µCT export is plain intensities with a window from its histogram, not a label map") {
  test::TempDir dir;
  const FloatVolume uct = test::syntheticMicroCt({72, 64, 56});
  const fs::path path = dir / "skull_uct.nrrd";
  REQUIRE(writeNrrd(path.string(), uct, ScalarKind::UInt8));
  auto loaded = loadImageFile(path.string());
  REQUIRE(loaded);
  CHECK((loaded->storedKind == ScalarKind::UInt8));
  CHECK(!looksLikeLabelMap(loaded->image));
  auto stored = toStoredVolume(*loaded, path.string());
  REQUIRE(stored);
  const IntensityModel& m = stored->intensity;
  CHECK(!m.hounsfield());
  CHECK(m.attenuationLike());
  CHECK(m.slope == 1);
  CHECK(m.intercept == 0);
  // The window spans air to bone: air (~14) at or just above its low end, bone (~196) below its top.
  const test::MicroCtLayout layout = test::microCtLayout(uct.dims());
  CHECK(m.window[0] <= layout.air + 5);
  CHECK(m.window[0] >= 0);
  CHECK(m.window[1] >= layout.bone - 10);
  CHECK(m.window[1] <= 255);
  for (std::size_t i = 0; i < uct.voxels.size(); i += 997) CHECK(m.valueOf(stored->volume.voxels[i]) == uct.voxels[i]);
}

TEST_CASE("uint16 µCT above 32767 is stored shifted, fractional MR-like values scaled; both give their values back") {
  test::TempDir dir;
  FloatVolume wide = test::syntheticMicroCt({40, 36, 30});
  for (float& v : wide.voxels) v = v * 256.0f + 100.0f;  // up to 65380: a 16-bit µCT
  const fs::path widePath = dir / "uct16.nrrd";
  REQUIRE(writeNrrd(widePath.string(), wide, ScalarKind::UInt16));
  auto loaded = loadImageFile(widePath.string());
  REQUIRE(loaded);
  auto stored = toStoredVolume(*loaded, widePath.string());
  REQUIRE(stored);
  CHECK(!stored->intensity.hounsfield());
  CHECK(stored->intensity.slope == 1);
  CHECK(stored->intensity.intercept != 0);
  for (std::size_t i = 0; i < wide.voxels.size(); ++i)
    REQUIRE(stored->intensity.valueOf(stored->volume.voxels[i]) == wide.voxels[i]);

  FloatVolume fractional = test::syntheticMicroCt({40, 36, 30});
  for (float& v : fractional.voxels) v = v / 255.0f * 3.5f + 0.25f;  // 0.25 … 3.75, not integers
  const fs::path mrPath = dir / "mr_like.nii.gz";
  REQUIRE(writeNiftiFloat(mrPath.string(), fractional));
  auto mr = loadImageFile(mrPath.string());
  REQUIRE(mr);
  auto mrStored = toStoredVolume(*mr, mrPath.string());
  REQUIRE(mrStored);
  CHECK(!mrStored->intensity.hounsfield());
  CHECK(mrStored->intensity.slope < 1e-3);
  for (std::size_t i = 0; i < fractional.voxels.size(); i += 31)
    CHECK(std::abs(mrStored->intensity.valueOf(mrStored->volume.voxels[i]) - fractional.voxels[i]) <=
          mrStored->intensity.slope);
}

TEST_CASE("Real CT reads as HU, its label map as a label map, and a DICOM MR as plain MR intensities") {
  if (!test::requireSharedData("intensity model on real files")) return;
  auto ct = loadImageFile(test::sharedData("totalsegmentator/ct_small.nii.gz").string());
  REQUIRE(ct);
  auto ctStored = toStoredVolume(*ct, "ct_small");
  REQUIRE(ctStored);
  CHECK(ctStored->intensity.hounsfield());
  CHECK(ctStored->intensity.window == std::array<float, 2>{-1000, 2000});
  auto seg = loadImageFile(test::sharedData("totalsegmentator/seg_small.nii.gz").string());
  REQUIRE(seg);
  CHECK(looksLikeLabelMap(seg->image));
  CHECK(!looksLikeLabelMap(ct->image));

  auto dicomCt = loadImageFile(test::sharedData("totalsegmentator/ct_dicom").string());
  REQUIRE(dicomCt);
  CHECK(dicomCt->modality == "CT");
  CHECK(dicomCt->rescaleGiven);

  // The head series relabelled as MR.
  test::TempDir dir;
  const fs::path mrDir = dir / "mr";
  fs::create_directories(mrDir);
  for (const auto& entry : fs::directory_iterator(test::sharedData("headsq/dicom"))) {
    if (entry.path().extension() != ".dcm") continue;
    REQUIRE(test::rewriteDicom(entry.path(), mrDir / entry.path().filename(),
                               [](DcmDataset& d) { d.putAndInsertString(DCM_Modality, "MR"); }));
  }
  DatasetFiles files;
  files.volumePath = mrDir.string();
  auto dataset = openDatasetFiles(files);
  REQUIRE(dataset);
  CHECK(!dataset->intensity.hounsfield());
  CHECK(dataset->intensity.modality == "MR");
  CHECK(!dataset->intensity.attenuationLike());
  CHECK(dataset->intensity.window[1] > dataset->intensity.window[0]);
  files.intensity = IntensityChoice::Hounsfield;
  auto forced = openDatasetFiles(files);
  REQUIRE(forced);
  CHECK(forced->intensity.hounsfield());
}

TEST_CASE("Label maps pass the label-map test: blocky labels and a binary mask") {
  Geometry g;
  g.dims = {30, 20, 10};
  FloatVolume labels(g, 0);
  for (int k = 0; k < 10; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 30; ++i) labels.at(i, j, k) = float((i / 6 + 5 * (j / 5)) % 23);
  CHECK(looksLikeLabelMap(labels));
  FloatVolume mask(g, 0);
  for (int i = 0; i < 30; i += 2) mask.at(i, 3, 3) = 1;
  CHECK(looksLikeLabelMap(mask));
  labels.at(3, 3, 3) = 2.5f;  // a fraction: an image
  CHECK(!looksLikeLabelMap(labels));
}
