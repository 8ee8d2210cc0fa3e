// DICOM series loading on the real series in ../shared/data.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>

#include "test_support.h"
#include "volume/dicom_series.h"
#include "volume/image_file.h"

using namespace at;

TEST_CASE("DICOM series: the JPEG 2000 CT loads as 512x512x20 at 0.977 x 0.977 x 2 mm") {
  if (!test::requireSharedData("DICOM series")) return;
  auto loaded = loadDicomSeries(test::sharedData("totalsegmentator/ct_dicom").string());
  REQUIRE_MESSAGE(loaded, (loaded ? "" : loaded.error().message));
  for (auto& n : loaded->notes) MESSAGE(n);
  const Geometry& g = loaded->image.geometry;
  CHECK(g.dims == Dims{512, 512, 20});
  CHECK(g.spacingMm[0] == doctest::Approx(0.9765625).epsilon(1e-6));
  CHECK(g.spacingMm[2] == doctest::Approx(2.0).epsilon(1e-6));
  auto [mn, mx] = std::minmax_element(loaded->image.voxels.begin(), loaded->image.voxels.end());
  MESSAGE(*mn << " " << *mx);
}
