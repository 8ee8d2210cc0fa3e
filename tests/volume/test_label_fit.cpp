// A label map that does not fit its CT (most labelled voxels on the air around the patient) is
// warned about with one line naming the label file; one that fits (air inside the body included)
// is not.
#include <doctest/doctest.h>

#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/image_file.h"
#include "volume/label_fit.h"
#include "volume/nifti_io.h"

using namespace at;

TEST_CASE("label fit: air enclosed by the body is inside, air around it is outside") {
  Geometry g;
  g.dims = {40, 30, 3};
  Volume ct(g, std::int16_t(-1000));
  LabelMap labels(g, 0);
  // A body ring (soft tissue) around a lung of air, labelled; a label blob outside on the air.
  for (int k = 0; k < 3; ++k)
    for (int j = 5; j < 25; ++j)
      for (int i = 5; i < 30; ++i) {
        const bool wall = i < 8 || i >= 27 || j < 8 || j >= 22;
        ct.at(i, j, k) = wall ? 40 : -850;
        if (!wall) labels.at(i, j, k) = 1;  // "lung": air, but inside
      }
  LabelFit fit = measureLabelFit(ct, labels, -500);
  CHECK(fit.labelled == 3 * 14 * 19);
  CHECK(fit.outsideBody == 0);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 32; i < 40; ++i) labels.at(i, j, k) = 2;
  fit = measureLabelFit(ct, labels, -500);
  CHECK(fit.outsideBody == 3 * 4 * 8);
  IntensityModel hu;
  CHECK(labelFitWarning(ct, hu, labels, "x.nii.gz").empty());  // 12 % outside: below 30 %
  IntensityModel plain;
  plain.unit = IntensityUnit::Plain;
  CHECK(labelFitWarning(ct, plain, labels, "x.nii.gz").empty());  // no air level for plain data
}

TEST_CASE("importing seg_small.nii.gz shifted off the body warns once, naming the file; in place it does not") {
  if (!test::requireSharedData("ct_small.nii.gz and seg_small.nii.gz")) return;
  DatasetFiles files;
  files.volumePath = test::sharedData("totalsegmentator/ct_small.nii.gz").string();
  files.labelsPath = test::sharedData("totalsegmentator/seg_small.nii.gz").string();
  auto fits = openDatasetFiles(files);
  REQUIRE_MESSAGE(fits, (fits ? "" : fits.error().message));
  const LabelFit good = measureLabelFit(fits->volume, fits->labels, -500);
  MESSAGE("in place: " << good.outsideBody << " of " << good.labelled << " labelled voxels outside the body");
  CHECK(good.outsideFraction() < 0.05);
  CHECK(fits->provenance.warnings.empty());

  // The same labels moved sideways by half the grid (what a wrong header origin does).
  const Dims d = fits->labels.dims();
  LabelMap shifted(fits->labels.geometry, 0);
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i + d.x / 2 < d.x; ++i) shifted.at(i + d.x / 2, j, k) = fits->labels.at(i, j, k);
  test::TempDir dir;
  const std::string path = (dir / "shifted_labels.nii.gz").string();
  REQUIRE(writeNiftiLabels(path, shifted));
  files.labelsPath = path;
  auto off = openDatasetFiles(files);
  REQUIRE_MESSAGE(off, (off ? "" : off.error().message));
  const LabelFit bad = measureLabelFit(off->volume, off->labels, -500);
  MESSAGE("shifted: " << bad.outsideBody << " of " << bad.labelled << " labelled voxels outside the body");
  REQUIRE(off->provenance.warnings.size() == 1);
  const std::string& warning = off->provenance.warnings[0];
  MESSAGE(warning);
  CHECK(warning.find(path) == 0);
  CHECK(warning.find('\n') == std::string::npos);
  CHECK(warning.find("outside the body") != std::string::npos);
}
