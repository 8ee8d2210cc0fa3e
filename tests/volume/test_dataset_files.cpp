// openDatasetFiles: volume + labels + names on real data, label alignment through both patient
// frames, structure naming, and that no patient identifier survives loading.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>

#include "dicom_test_files.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/dicom_seg.h"
#include "volume/image_file.h"
#include "volume/nifti_io.h"
#include "volume/resample.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

struct Alignment {
  double boneAbove100 = 0;      // of voxels labelled vertebrae_* or rib_*
  double organsSoftTissue = 0;  // of voxels labelled liver or spleen, in −100…250 HU
};

Alignment measureAlignment(const Volume& ct, const LabelMap& labels, const std::set<std::uint16_t>& bone,
                           const std::set<std::uint16_t>& organs) {
  std::size_t boneCount = 0, boneDense = 0, organCount = 0, organSoft = 0;
  for (std::size_t v = 0; v < ct.voxels.size(); ++v) {
    const std::uint16_t label = labels.voxels[v];
    const int hu = ct.voxels[v];
    if (bone.count(label)) {
      ++boneCount;
      boneDense += hu > 100;
    } else if (organs.count(label)) {
      ++organCount;
      organSoft += hu >= -100 && hu <= 250;
    }
  }
  REQUIRE(boneCount > 1000);
  REQUIRE(organCount > 1000);
  return {double(boneDense) / double(boneCount), double(organSoft) / double(organCount)};
}

// Label values of the TotalSegmentator names: bone = vertebrae_* and rib_*, organs = liver, spleen.
void totalSegmentatorLabels(std::set<std::uint16_t>& bone, std::set<std::uint16_t>& organs) {
  auto names = loadLabelNames(test::sharedData("totalsegmentator/labels.json").string());
  REQUIRE_MESSAGE(names, (names ? "" : names.error().message));
  for (const auto& [value, name] : *names) {
    if (name.rfind("vertebrae_", 0) == 0 || name.rfind("rib_", 0) == 0) bone.insert(value);
    if (name == "liver" || name == "spleen") organs.insert(value);
  }
  REQUIRE(bone.size() > 10);
  REQUIRE(organs.size() == 2);
}

// Every string a Dataset carries, for identifier checks.
std::vector<std::string> allStrings(const Dataset& d) {
  std::vector<std::string> out = {d.id, d.displayName, d.species, d.provenance.source, d.provenance.labelsSource};
  out.insert(out.end(), d.provenance.notes.begin(), d.provenance.notes.end());
  for (const Structure& s : d.structures) {
    out.push_back(s.id);
    out.push_back(s.displayName);
    out.push_back(s.system);
    out.push_back(s.description);
  }
  return out;
}

bool oneLine(const std::string& s) { return !s.empty() && s.find('\n') == std::string::npos; }

}  // namespace

TEST_CASE("Dataset files: seg_dicom.nii.gz lands on bone and soft tissue of the DICOM series through both affines") {
  if (!test::requireSharedData("label alignment (seg_dicom.nii.gz on ct_dicom)")) return;
  std::set<std::uint16_t> bone, organs;
  totalSegmentatorLabels(bone, organs);

  DatasetFiles files;
  files.volumePath = test::sharedData("totalsegmentator/ct_dicom").string();
  files.labelsPath = test::sharedData("totalsegmentator/seg_dicom.nii.gz").string();
  files.namesPath = test::sharedData("totalsegmentator/labels.json").string();
  auto dataset = openDatasetFiles(files);
  REQUIRE_MESSAGE(dataset, (dataset ? "" : dataset.error().message));
  CHECK(dataset->labels.geometry.sameGridAs(dataset->volume.geometry));
  bool resampledNote = false;
  for (const std::string& note : dataset->provenance.notes) resampledNote |= note.find("resampled") != std::string::npos;
  CHECK(resampledNote);

  const Alignment aligned = measureAlignment(dataset->volume, dataset->labels, bone, organs);
  MESSAGE("through both affines: bone > 100 HU " << aligned.boneAbove100 << ", liver/spleen in −100…250 HU "
                                                 << aligned.organsSoftTissue);
  CHECK(aligned.boneAbove100 >= 0.75);
  CHECK(aligned.organsSoftTissue >= 0.95);

  // Ignoring the NIfTI affine (labels copied index for index) must fail the same check.
  auto raw = loadImageFile(files.labelsPath);
  REQUIRE(raw);
  auto rawLabels = toLabelMap(*raw, files.labelsPath);
  REQUIRE(rawLabels);
  REQUIRE(rawLabels->geometry.dims == dataset->volume.geometry.dims);
  const Alignment ignored = measureAlignment(dataset->volume, *rawLabels, bone, organs);
  MESSAGE("index for index: bone > 100 HU " << ignored.boneAbove100 << ", liver/spleen in −100…250 HU "
                                            << ignored.organsSoftTissue);
  CHECK_FALSE((ignored.boneAbove100 >= 0.75 && ignored.organsSoftTissue >= 0.95));
  CHECK(ignored.boneAbove100 < 0.5);

  // Structures: only labels present, named from labels.json, snake_case ids.
  REQUIRE(dataset->structures.size() >= 20);
  const Structure* liver = dataset->findStructure("liver");
  REQUIRE(liver != nullptr);
  CHECK(liver->displayName == "Liver");
  std::vector<std::size_t> counts(65536, 0);
  for (std::uint16_t v : dataset->labels.voxels) ++counts[v];
  for (const Structure& s : dataset->structures) {
    CHECK(counts[s.label] > 0);
    CHECK(s.id.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") == std::string::npos);
  }
  std::size_t present = 0;
  for (std::size_t v = 1; v < counts.size(); ++v) present += counts[v] > 0;
  CHECK(dataset->structures.size() == present);
}

TEST_CASE("Dataset files: a DICOM SEG on the CT's own grid gives a named structure without resampling") {
  if (!test::requireSharedData("dataset from DICOM + SEG")) return;
  DatasetFiles files;
  files.volumePath = test::sharedData("dcmqi/ct-3slice").string();
  files.labelsPath = test::sharedData("dcmqi/liver.dcm").string();
  auto dataset = openDatasetFiles(files);
  REQUIRE_MESSAGE(dataset, (dataset ? "" : dataset.error().message));
  CHECK(dataset->id == "ct_3slice");
  CHECK(dataset->volume.geometry.dims == Dims{512, 512, 3});
  for (const std::string& note : dataset->provenance.notes) CHECK(note.find("resampled") == std::string::npos);
  REQUIRE(dataset->structures.size() == 1);
  CHECK(dataset->structures[0].id == "liver");
  CHECK(dataset->structures[0].displayName == "Liver");
  CHECK(dataset->structures[0].label == 1);
  CHECK(dataset->provenance.labelsSource == files.labelsPath);

  auto seg = loadDicomSeg(files.labelsPath);
  REQUIRE(seg);
  const auto segCount = std::count_if(seg->image.voxels.begin(), seg->image.voxels.end(), [](float v) { return v != 0; });
  const auto mapCount = std::count(dataset->labels.voxels.begin(), dataset->labels.voxels.end(), std::uint16_t(1));
  CHECK(mapCount == segCount);
}

TEST_CASE("Dataset files: labels one slice off the CT are resampled onto the CT's slices") {
  if (!test::requireSharedData("label resampling")) return;
  test::TempDir dir("at-dicom-shift");
  const fs::path shifted = dir / "liver_shifted.dcm";
  REQUIRE(test::rewriteDicom(test::sharedData("dcmqi/liver.dcm"), shifted, [](DcmDataset& d) {
    test::editFramePositions(d, [](std::array<double, 3> p) { return std::array<double, 3>{p[0], p[1], p[2] + 1.0}; });
  }));
  DatasetFiles files;
  files.volumePath = test::sharedData("dcmqi/ct-3slice").string();
  files.labelsPath = shifted.string();
  auto dataset = openDatasetFiles(files);
  REQUIRE_MESSAGE(dataset, (dataset ? "" : dataset.error().message));
  auto seg = loadDicomSeg(test::sharedData("dcmqi/liver.dcm").string());
  REQUIRE(seg);
  // The SEG's slice k now sits at the CT's slice k + 1; CT slice 0 has no label left.
  const std::size_t slice = 512 * 512;
  std::size_t differing = 0, inSlice0 = 0;
  for (std::size_t p = 0; p < slice; ++p) {
    inSlice0 += dataset->labels.voxels[p] != 0;
    for (int k = 1; k < 3; ++k)
      differing += (dataset->labels.voxels[k * slice + p] != 0) != (seg->image.voxels[(k - 1) * slice + p] != 0);
  }
  CHECK(inSlice0 == 0);
  CHECK(differing == 0);
  bool resampledNote = false;
  for (const std::string& note : dataset->provenance.notes) resampledNote |= note.find("resampled") != std::string::npos;
  CHECK(resampledNote);
}

TEST_CASE("Dataset files: labels that do not overlap the volume are refused with both paths named") {
  if (!test::requireSharedData("label overlap")) return;
  test::TempDir dir("at-dicom-far");
  const fs::path far = dir / "liver_far.dcm";
  REQUIRE(test::rewriteDicom(test::sharedData("dcmqi/liver.dcm"), far, [](DcmDataset& d) {
    test::editFramePositions(d, [](std::array<double, 3> p) { return std::array<double, 3>{p[0], p[1], p[2] + 500.0}; });
  }));
  DatasetFiles files;
  files.volumePath = test::sharedData("dcmqi/ct-3slice").string();
  files.labelsPath = far.string();
  auto dataset = openDatasetFiles(files);
  REQUIRE(!dataset);
  const std::string& message = dataset.error().message;
  INFO(message);
  CHECK(oneLine(message));
  CHECK(message.find(far.string() + " does not overlap " + files.volumePath) == 0);
  CHECK(message.find("patient frame") != std::string::npos);
}

TEST_CASE("Dataset files: structures are named from the names JSON, else label_N") {
  if (!test::requireSharedData("structure naming")) return;
  DatasetFiles files;
  files.volumePath = test::sharedData("dcmqi/ct-3slice").string();
  files.labelsPath = test::sharedData("dcmqi/liver_seg.nrrd").string();
  auto unnamed = openDatasetFiles(files);
  REQUIRE_MESSAGE(unnamed, (unnamed ? "" : unnamed.error().message));
  REQUIRE(unnamed->structures.size() == 1);
  const std::uint16_t label = unnamed->structures[0].label;
  CHECK(unnamed->structures[0].id == "label_" + std::to_string(label));

  test::TempDir dir("at-dicom-names");
  files.namesPath = (dir / "names.json").string();
  std::ofstream(files.namesPath) << "{ \"" << label << "\": \"Liver (left lobe)\", \"" << label + 1 << "\": \"absent\" }";
  auto named = openDatasetFiles(files);
  REQUIRE_MESSAGE(named, (named ? "" : named.error().message));
  REQUIRE(named->structures.size() == 1);
  CHECK(named->structures[0].id == "liver_left_lobe");
  CHECK(named->structures[0].displayName == "Liver (left lobe)");
}

TEST_CASE("Dataset files: no patient identifier from the DICOM headers survives loading") {
  if (!test::requireSharedData("patient identifiers")) return;
  const std::string marker = "QQMARKER7731";
  auto identify = [&](DcmDataset& d) {
    for (const DcmTagKey& tag : {DCM_PatientName, DCM_PatientID, DCM_PatientBirthDate, DCM_InstitutionName,
                                 DCM_AccessionNumber, DCM_StudyDate, DCM_SeriesDate, DCM_ReferringPhysicianName,
                                 DCM_StudyDescription, DCM_SeriesDescription})
      d.putAndInsertString(tag, marker.c_str());
  };
  test::TempDir dir("at-dicom-phi");
  const fs::path ct = dir / "ct";
  fs::create_directory(ct);
  for (const auto& entry : fs::directory_iterator(test::sharedData("dcmqi/ct-3slice")))
    REQUIRE(test::rewriteDicom(entry.path(), ct / entry.path().filename(), identify));
  const fs::path seg = dir / "seg.dcm";
  REQUIRE(test::rewriteDicom(test::sharedData("dcmqi/liver.dcm"), seg, identify));
  REQUIRE(test::dicomString(ct / "01.dcm", DCM_PatientName) == marker);
  REQUIRE(test::dicomString(seg, DCM_PatientID) == marker);

  DatasetFiles files;
  files.volumePath = ct.string();
  files.labelsPath = seg.string();
  auto dataset = openDatasetFiles(files);
  REQUIRE_MESSAGE(dataset, (dataset ? "" : dataset.error().message));
  for (const std::string& s : allStrings(*dataset)) CHECK_MESSAGE(s.find(marker) == std::string::npos, s);

  for (const fs::path& path : {ct, seg}) {
    auto image = loadImageFile(path.string());
    REQUIRE(image);
    for (const std::string& note : image->notes) CHECK_MESSAGE(note.find(marker) == std::string::npos, note);
    for (const SegmentInfo& s : image->segments) CHECK(s.name.find(marker) == std::string::npos);
  }
}

// A label map on a finer grid than its volume can hold a structure smaller than the volume's voxels;
// resampled onto the volume it has no voxel left. It is not dropped silently: one warning line names
// the label file and the structure (name, label, voxels); every label that kept a voxel is a structure.
TEST_CASE("Dataset files: labels lost to resampling onto a coarser volume are named in one warning") {
  if (!test::requireSharedData("ct_small.nii.gz and seg_small.nii.gz")) return;
  DatasetFiles files;
  files.volumePath = test::sharedData("totalsegmentator/ct_small.nii.gz").string();
  files.labelsPath = test::sharedData("totalsegmentator/seg_small.nii.gz").string();
  auto coarse = openDatasetFiles(files);
  REQUIRE_MESSAGE(coarse, (coarse ? "" : coarse.error().message));
  // The reference labels on a grid of half the spacing (same origin: every other fine voxel centre
  // is a coarse one), plus a two-voxel "accessory spleen" on fine voxels between coarse centres.
  Geometry fine = coarse->labels.geometry;
  for (auto& s : fine.spacingMm) s /= 2;
  fine.dims = {fine.dims.x * 2, fine.dims.y * 2, fine.dims.z * 2};
  auto refined = resampleLabelsNearest(coarse->labels, fine);
  REQUIRE(refined);
  const std::uint16_t accessory = 200;
  refined->at(61, 51, 15) = accessory;
  refined->at(61, 51, 17) = accessory;
  test::TempDir dir("at-lost-labels");
  files.labelsPath = (dir / "fine_labels.nii.gz").string();
  REQUIRE(writeNiftiLabels(files.labelsPath, *refined));
  files.namesPath = (dir / "names.json").string();
  std::ofstream(files.namesPath) << "{ \"" << accessory << "\": \"Accessory spleen\" }";
  auto dataset = openDatasetFiles(files);
  REQUIRE_MESSAGE(dataset, (dataset ? "" : dataset.error().message));
  CHECK(dataset->structures.size() == coarse->structures.size());
  CHECK_FALSE(dataset->findStructure("accessory_spleen"));
  REQUIRE(dataset->provenance.warnings.size() == 1);
  const std::string& warning = dataset->provenance.warnings[0];
  INFO(warning);
  CHECK(oneLine(warning));
  CHECK(warning.find(files.labelsPath + ": 1 label lost every voxel") == 0);
  CHECK(warning.find("200 'Accessory spleen' (2 voxels)") != std::string::npos);
  CHECK(warning.find("3 x 3 x 3 mm grid") != std::string::npos);
  // Labelled on the volume's own grid, nothing is lost and nothing is said.
  refined->at(60, 50, 16) = accessory;
  files.labelsPath = (dir / "fine_labels_kept.nii.gz").string();
  REQUIRE(writeNiftiLabels(files.labelsPath, *refined));
  auto kept = openDatasetFiles(files);
  REQUIRE(kept);
  CHECK(kept->provenance.warnings.empty());
  CHECK(kept->findStructure("accessory_spleen"));
}
