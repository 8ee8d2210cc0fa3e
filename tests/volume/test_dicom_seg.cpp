// DICOM SEG on the dcmqi samples: segments, frame geometry, agreement with the NRRD label maps.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "test_support.h"
#include "volume/dicom_seg.h"
#include "volume/dicom_series.h"
#include "volume/image_file.h"
#include "volume/nrrd_io.h"

using namespace at;

namespace {

// Number of voxels of `reference` whose "labelled" state differs from the voxel of `other` at the
// same LPS position (positions outside `other` count as unlabelled there).
std::size_t differingVoxels(const FloatVolume& reference, const FloatVolume& other,
                            const std::function<bool(float, float)>& same) {
  std::size_t differing = 0;
  const Dims& d = reference.geometry.dims;
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const Vec3 q = other.geometry.patientToIndex(reference.geometry.indexToPatient({double(i), double(j), double(k)}));
        const int a = int(std::lround(q[0])), b = int(std::lround(q[1])), c = int(std::lround(q[2]));
        const float there = other.geometry.dims.contains(a, b, c) ? other.at(a, b, c) : 0.0f;
        if (!same(reference.at(i, j, k), there)) ++differing;
      }
  return differing;
}

std::size_t labelled(const FloatVolume& v) {
  return std::size_t(std::count_if(v.voxels.begin(), v.voxels.end(), [](float x) { return x != 0; }));
}

}  // namespace

TEST_CASE("DICOM SEG: liver.dcm has one segment 'Liver' on the CT's three slice positions") {
  if (!test::requireSharedData("DICOM SEG")) return;
  const std::string path = test::sharedData("dcmqi/liver.dcm").string();
  CHECK(isDicomSegFile(path));
  auto seg = loadDicomSeg(path);
  REQUIRE_MESSAGE(seg, (seg ? "" : seg.error().message));
  REQUIRE(seg->segments.size() == 1);
  CHECK(seg->segments[0].label == 1);
  CHECK(seg->segments[0].name == "Liver");
  // RecommendedDisplayCIELabValue 41661\41167\40792 is a light red-brown, not the default white.
  CHECK(seg->segments[0].colour[0] > seg->segments[0].colour[2]);

  auto ct = loadDicomSeries(test::sharedData("dcmqi/ct-3slice").string());
  REQUIRE(ct);
  CHECK(seg->image.geometry.sameGridAs(ct->image.geometry, 1e-3));
  CHECK(labelled(seg->image) > 1000);
}

TEST_CASE("DICOM SEG: the liver in liver.dcm covers the same patient-frame voxels as liver_seg.nrrd") {
  if (!test::requireSharedData("DICOM SEG vs NRRD")) return;
  auto seg = loadImageFile(test::sharedData("dcmqi/liver.dcm").string());
  auto nrrd = loadImageFile(test::sharedData("dcmqi/liver_seg.nrrd").string());
  REQUIRE_MESSAGE(seg, (seg ? "" : seg.error().message));
  REQUIRE_MESSAGE(nrrd, (nrrd ? "" : nrrd.error().message));
  const std::size_t count = labelled(nrrd->image);
  REQUIRE(count > 1000);
  CHECK(labelled(seg->image) == count);
  auto bothLabelled = [](float a, float b) { return (a != 0) == (b != 0); };
  CHECK(differingVoxels(nrrd->image, seg->image, bothLabelled) == 0);
  CHECK(differingVoxels(seg->image, nrrd->image, bothLabelled) == 0);
}

TEST_CASE("DICOM SEG: partial_overlaps.dcm loads five named, overlapping segments") {
  if (!test::requireSharedData("DICOM SEG overlaps")) return;
  auto seg = loadDicomSeg(test::sharedData("dcmqi/partial_overlaps.dcm").string());
  REQUIRE_MESSAGE(seg, (seg ? "" : seg.error().message));
  const std::vector<std::string> names = {"GREEN", "ORANGE", "PURPLE", "LIGHT_BLUE", "DARK_BLUE"};
  REQUIRE(seg->segments.size() == names.size());
  for (std::size_t s = 0; s < names.size(); ++s) {
    CHECK(seg->segments[s].label == s + 1);
    CHECK(seg->segments[s].name == names[s]);
  }
  bool overlapNoted = false;
  for (const std::string& note : seg->notes) overlapNoted |= note.find("higher segment number wins") != std::string::npos;
  CHECK(overlapNoted);
  CHECK(seg->image.geometry.dims == Dims{512, 512, 3});

  // The three NRRD layers dcmqi made it from: together they label exactly the SEG's voxels.
  std::vector<LoadedImage> layers;
  for (int n = 1; n <= 3; ++n) {
    auto layer = loadImageFile(test::sharedData("dcmqi/partial_overlaps-" + std::to_string(n) + ".nrrd").string());
    REQUIRE_MESSAGE(layer, (layer ? "" : layer.error().message));
    REQUIRE(layer->image.geometry.sameGridAs(seg->image.geometry, 1e-3));
    layers.push_back(std::move(*layer));
  }
  std::size_t differing = 0;
  for (std::size_t v = 0; v < seg->image.voxels.size(); ++v) {
    bool inAnyLayer = false;
    for (const LoadedImage& layer : layers) inAnyLayer |= layer.image.voxels[v] != 0;
    if (inAnyLayer != (seg->image.voxels[v] != 0)) ++differing;
  }
  CHECK(differing == 0);
  const auto notALabel = std::count_if(seg->image.voxels.begin(), seg->image.voxels.end(),
                                       [](float v) { return v < 0 || v > 5 || v != std::floor(v); });
  CHECK(notALabel == 0);
}

TEST_CASE("DICOM SEG: a CT image is not a segmentation, and a SEG file is not a series") {
  if (!test::requireSharedData("DICOM SEG")) return;
  const std::string ct = test::sharedData("dcmqi/ct-3slice/01.dcm").string();
  CHECK_FALSE(isDicomSegFile(ct));
  auto notSeg = loadDicomSeg(ct);
  REQUIRE(!notSeg);
  CHECK(notSeg.error().message.find("01.dcm") != std::string::npos);
  CHECK(notSeg.error().message.find("not a DICOM Segmentation") != std::string::npos);
}
