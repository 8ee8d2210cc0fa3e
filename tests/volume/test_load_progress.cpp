// Progress and cancellation of long loads (ImageLoadOptions::progress/cancel, DatasetLoadControl):
// what the desktop app's import window shows and how its Cancel button stops a load.
#include <doctest/doctest.h>

#include <atomic>
#include <mutex>
#include <utility>
#include <vector>

#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/image_file.h"

using namespace at;

namespace {

struct Calls {
  std::mutex mutex;
  std::vector<std::pair<std::size_t, std::size_t>> list;
  void operator()(std::size_t done, std::size_t total) {
    std::lock_guard lock(mutex);
    list.emplace_back(done, total);
  }
};

// Starts at 0 of `total`, rises by whole steps (by one for slices and files) and ends at `total`.
void checkProgress(const std::vector<std::pair<std::size_t, std::size_t>>& calls, std::size_t total, bool byOne) {
  REQUIRE(calls.size() >= 2);
  CHECK(calls.front() == std::make_pair(std::size_t(0), total));
  CHECK(calls.back() == std::make_pair(total, total));
  for (std::size_t i = 1; i < calls.size(); ++i) {
    CHECK(calls[i].second == total);
    CHECK(calls[i].first > calls[i - 1].first);
    if (byOne) CHECK(calls[i].first == calls[i - 1].first + 1);
  }
}

}  // namespace

TEST_CASE("LoadProgress_DicomSeries_CountsEachSliceOnceUpToTheSeriesLength") {
  if (!test::requireSharedData("DICOM load progress")) return;
  Calls calls;
  ImageLoadOptions options;
  options.progress = std::ref(calls);
  auto loaded = loadImageFile(test::sharedData("totalsegmentator/ct_dicom").string(), options);
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  REQUIRE(loaded->image.geometry.dims.z == 20);
  checkProgress(calls.list, 20, true);
}

TEST_CASE("LoadProgress_DetachedNrrd_CountsItsDataFiles") {
  if (!test::requireSharedData("NRRD load progress")) return;
  Calls calls;
  ImageLoadOptions options;
  options.progress = std::ref(calls);
  auto loaded = loadImageFile(test::sharedData("headsq/nrrd/quarter.nhdr").string(), options);
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  checkProgress(calls.list, 93, true);
}

TEST_CASE("LoadProgress_Nifti_CountsTheVoxelBytes") {
  if (!test::requireSharedData("NIfTI load progress")) return;
  Calls calls;
  ImageLoadOptions options;
  options.progress = std::ref(calls);
  auto loaded = loadImageFile(test::sharedData("totalsegmentator/ct_small.nii.gz").string(), options);
  REQUIRE_MESSAGE(loaded, loaded.error().message);
  checkProgress(calls.list, 122 * 101 * 30 * 2, false);  // int16
}

TEST_CASE("LoadCancel_SetDuringADicomSeries_StopsItWithAMessageNamingTheFolder") {
  if (!test::requireSharedData("DICOM load cancel")) return;
  const std::string folder = test::sharedData("totalsegmentator/ct_dicom").string();
  std::atomic<bool> cancel{false};
  std::size_t calls = 0;
  ImageLoadOptions options;
  options.cancel = &cancel;
  options.progress = [&](std::size_t done, std::size_t) {
    ++calls;  // never concurrent (contract)
    if (done == 3) cancel = true;
  };
  auto loaded = loadImageFile(folder, options);
  REQUIRE(!loaded);
  CHECK(loaded.error().message == folder + ": loading cancelled");
  // The decoding threads stop at their next slice: far fewer than 20 slices were read.
  CHECK(calls < 1 + 20);
}

TEST_CASE("LoadCancel_SetBeforeTheLoad_ReadsNoVoxelsOfAnyFormat") {
  if (!test::requireSharedData("load cancel")) return;
  std::atomic<bool> cancel{true};
  for (const char* file : {"totalsegmentator/ct_dicom", "headsq/nrrd/quarter.nhdr", "totalsegmentator/ct_small.nii.gz"}) {
    CAPTURE(file);
    ImageLoadOptions options;
    options.cancel = &cancel;
    std::size_t read = 0;
    options.progress = [&](std::size_t done, std::size_t) { read = std::max(read, done); };
    auto loaded = loadImageFile(test::sharedData(file).string(), options);
    REQUIRE(!loaded);
    CHECK(loaded.error().message.find("loading cancelled") != std::string::npos);
    CHECK(read == 0);
  }
}

TEST_CASE("DatasetLoadControl_ReportsEachPartAsItStarts_AndACancelStopsTheLoad") {
  if (!test::requireSharedData("dataset load control")) return;
  const auto ts = test::sharedData("totalsegmentator");
  DatasetFiles files;
  files.volumePath = (ts / "ct_dicom").string();
  files.labelsPath = (ts / "seg_dicom.nii.gz").string();

  std::vector<DatasetLoadPart> parts;
  DatasetLoadControl control;
  control.progress = [&](DatasetLoadPart part, std::size_t done, std::size_t total) {
    if (done == 0 && total == 0) parts.push_back(part);
  };
  SUBCASE("all parts, the labels resampled onto the DICOM grid") {
    auto dataset = openDatasetFiles(files, control);
    REQUIRE_MESSAGE(dataset, dataset.error().message);
    CHECK(parts == std::vector<DatasetLoadPart>{DatasetLoadPart::Volume, DatasetLoadPart::Labels,
                                                DatasetLoadPart::Resampling});
  }
  SUBCASE("cancelled as the labels start: their loader stops, nothing is resampled") {
    std::atomic<bool> cancel{false};
    control.cancel = &cancel;
    control.progress = [&](DatasetLoadPart part, std::size_t done, std::size_t total) {
      if (done == 0 && total == 0) parts.push_back(part);
      if (part == DatasetLoadPart::Labels) cancel = true;
    };
    auto dataset = openDatasetFiles(files, control);
    REQUIRE(!dataset);
    CHECK(dataset.error().message == files.labelsPath + ": loading cancelled");
    CHECK(parts == std::vector<DatasetLoadPart>{DatasetLoadPart::Volume, DatasetLoadPart::Labels});
  }
}
