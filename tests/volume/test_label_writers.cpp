// Label writers (volume/label_writers.h): a NIfTI label map with its names JSON and a Slicer
// .seg.nrrd read back through the app's own loaders (openDatasetFiles, loadNrrd) with values,
// names, colours and geometry intact; a two-layer .seg.nrrd as Slicer writes overlapping segments.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <random>

#include "io_test_files.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/label_writers.h"
#include "volume/nifti_io.h"
#include "volume/nrrd_io.h"

using namespace at;
using namespace at::test;

namespace {

Structure structure(std::uint16_t label, const std::string& id, const std::string& name, std::array<float, 3> colour) {
  Structure s;
  s.label = label;
  s.id = id;
  s.displayName = name;
  s.colour = colour;
  return s;
}

// Random blobs of the structures' labels (and one unnamed value, 9) on an oblique grid.
LabelMap randomLabels(std::mt19937_64& rng, Dims dims, const std::vector<std::uint16_t>& values) {
  LabelMap labels(randomObliqueGeometry(rng, dims), 0);
  std::uniform_int_distribution<int> pick(0, int(values.size()) - 1);
  std::uniform_int_distribution<int> coordinate(0, 1 << 20);
  // Every value is present (the writers choose their type and extents by what is present): the
  // last blobs take each value once, and a value any later blob covered is put back on one voxel.
  const int blobs = 12, firstFixed = blobs - int(values.size());
  for (int blob = 0; blob < blobs; ++blob) {
    const int ci = coordinate(rng) % dims.x, cj = coordinate(rng) % dims.y, ck = coordinate(rng) % dims.z;
    const std::uint16_t value = blob >= firstFixed ? values[std::size_t(blob - firstFixed)] : values[std::size_t(pick(rng))];
    for (int k = 0; k < dims.z; ++k)
      for (int j = 0; j < dims.y; ++j)
        for (int i = 0; i < dims.x; ++i)
          if ((i - ci) * (i - ci) + (j - cj) * (j - cj) + (k - ck) * (k - ck) <= 6) labels.at(i, j, k) = value;
  }
  for (std::size_t n = 0; n < values.size(); ++n)
    if (std::find(labels.voxels.begin(), labels.voxels.end(), values[n]) == labels.voxels.end()) labels.voxels[n] = values[n];
  return labels;
}

const SegmentInfo* segmentWithLabel(const std::vector<SegmentInfo>& segments, std::uint16_t label) {
  for (const SegmentInfo& s : segments)
    if (s.label == label) return &s;
  return nullptr;
}

}  // namespace

TEST_CASE("A NIfTI label map with its names JSON opens as the dataset's labels and named structures") {
  std::mt19937_64 rng(freshSeed("label writers nifti"));
  TempDir dir;
  const std::vector<Structure> structures = {structure(1, "liver", "liver", {0.8f, 0.4f, 0.3f}),
                                             structure(300, "spleen", "spleen", {0.2f, 0.3f, 0.9f})};
  const LabelMap labels = randomLabels(rng, {14, 11, 9}, {1, 300});
  FloatVolume ct(labels.geometry);
  for (std::size_t i = 0; i < ct.voxels.size(); ++i) ct.voxels[i] = labels.voxels[i] ? 60.0f : -900.0f;
  REQUIRE(writeNiftiFloat((dir / "ct.nii.gz").string(), ct));
  REQUIRE(writeNiftiLabels((dir / "labels.nii.gz").string(), labels));
  REQUIRE(writeLabelNames((dir / "names.json").string(), structures));

  const auto names = nlohmann::json::parse(readBytes(dir / "names.json"));
  CHECK(names == nlohmann::json{{"1", "liver"}, {"300", "spleen"}});

  DatasetFiles files;
  files.volumePath = (dir / "ct.nii.gz").string();
  files.labelsPath = (dir / "labels.nii.gz").string();
  files.namesPath = (dir / "names.json").string();
  auto dataset = openDatasetFiles(files);
  REQUIRE_MESSAGE(dataset, dataset.error().message);
  CHECK(dataset->labels.voxels == labels.voxels);
  REQUIRE(dataset->structures.size() == 2);
  CHECK(dataset->structures[0].label == 1);
  CHECK(dataset->structures[0].id == "liver");
  CHECK(dataset->structures[1].label == 300);
  CHECK(dataset->structures[1].id == "spleen");
}

TEST_CASE("A .seg.nrrd reads back with its values, geometry, segment names, colours and Slicer's keys") {
  std::mt19937_64 rng(freshSeed("label writers seg.nrrd"));
  TempDir dir;
  for (const bool wide : {false, true}) {
    CAPTURE(wide);
    const std::uint16_t second = wide ? 300 : 7;
    const std::vector<Structure> structures = {structure(second, "spleen", "Spleen", {0.2f, 0.3f, 0.9f}),
                                               structure(1, "liver", "Liver", {0.8f, 0.4f, 0.3f}),
                                               structure(4, "absent", "Absent", {0.5f, 0.5f, 0.5f})};
    const LabelMap labels = randomLabels(rng, {13, 10, 8}, {1, second, 9});
    const auto path = dir / (wide ? "wide.seg.nrrd" : "narrow.seg.nrrd");
    auto written = writeSegNrrd(path.string(), labels, structures);
    REQUIRE_MESSAGE(written, written.error().message);

    const std::string text = readBytes(path);
    const std::string header = text.substr(0, text.find("\n\n"));
    CHECK(header.find(wide ? "type: ushort\n" : "type: uint8\n") != std::string::npos);
    CHECK(header.find("Segmentation_MasterRepresentation:=Binary labelmap") != std::string::npos);
    CHECK(header.find("Segment0_LabelValue:=1\n") != std::string::npos);  // sorted by label value
    CHECK(header.find("Segment0_Layer:=0\n") != std::string::npos);
    CHECK(header.find("Segment2_Extent:=0 -1 0 -1 0 -1\n") == std::string::npos);  // 'absent' is Segment1
    CHECK(header.find("Segment1_Extent:=0 -1 0 -1 0 -1\n") != std::string::npos);

    auto loaded = loadNrrd(path.string());
    REQUIRE_MESSAGE(loaded, loaded.error().message);
    CHECK((loaded->storedKind == (wide ? ScalarKind::UInt16 : ScalarKind::UInt8)));
    CHECK(loaded->image.geometry.dims == labels.dims());
    CHECK(maxAbsDifference(loaded->image.geometry.direction, labels.geometry.direction) < 1e-12);
    CHECK(maxAbsDifference(loaded->image.geometry.spacingMm, labels.geometry.spacingMm) < 1e-12);
    CHECK(maxAbsDifference(loaded->image.geometry.originMm, labels.geometry.originMm) < 1e-12);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < labels.voxels.size(); ++i) differ += loaded->image.voxels[i] != float(labels.voxels[i]);
    CHECK(differ == 0);
    REQUIRE(loaded->segments.size() == 3);
    for (const Structure& s : structures) {
      const SegmentInfo* segment = segmentWithLabel(loaded->segments, s.label);
      REQUIRE_MESSAGE(segment, s.id);
      CHECK(segment->name == s.displayName);
      for (int c = 0; c < 3; ++c) CHECK(segment->colour[std::size_t(c)] == doctest::Approx(s.colour[std::size_t(c)]));
    }
  }
}

TEST_CASE("A two-layer .seg.nrrd (overlapping segments) merges into one label map, later layer on top") {
  TempDir dir;
  // Layer 0 holds 'liver' (value 1), layer 1 'tumour' (value 1 too: values are per layer) on a
  // 3x2x2 grid; the tumour overlaps the liver in one voxel.
  const std::vector<int> layer0 = {1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0};
  const std::vector<int> layer1 = {0, 1, 1, 0, 0, 0, 0, 0, 0, 0, 0, 1};
  const std::string header =
      "NRRD0004\ntype: unsigned char\ndimension: 4\nspace: left-posterior-superior\nsizes: 2 3 2 2\n"
      "space directions: none (1,0,0) (0,1,0) (0,0,2)\nkinds: list domain domain domain\n"
      "encoding: raw\nspace origin: (0,0,0)\n"
      "Segment0_ID:=liver\nSegment0_Name:=liver\nSegment0_Color:=0.9 0.5 0.4\nSegment0_LabelValue:=1\n"
      "Segment0_Layer:=0\n"
      "Segment1_ID:=tumour\nSegment1_Name:=tumour\nSegment1_Color:=0.9 0.9 0.1\nSegment1_LabelValue:=1\n"
      "Segment1_Layer:=1\n\n";
  std::string data;
  for (std::size_t v = 0; v < layer0.size(); ++v) data += char(layer0[v]), data += char(layer1[v]);
  writeBytes(dir / "layers.seg.nrrd", header + data);
  auto loaded = loadNrrd((dir / "layers.seg.nrrd").string());
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  CHECK(loaded->image.geometry.dims == Dims{3, 2, 2});
  REQUIRE(loaded->segments.size() == 2);
  const std::uint16_t liver = loaded->segments[0].label, tumour = loaded->segments[1].label;
  CHECK(loaded->segments[0].name == "liver");
  CHECK(loaded->segments[1].name == "tumour");
  CHECK(liver != tumour);
  const std::vector<float> expected = {float(liver), float(tumour), float(tumour), 0, 0, 0,
                                       float(liver), 0, 0, 0, 0, float(tumour)};
  CHECK(loaded->image.voxels == expected);
  bool noted = false;
  for (const std::string& note : loaded->notes) noted = noted || note.find("merged 2 segmentation layers") != std::string::npos;
  CHECK(noted);
}
