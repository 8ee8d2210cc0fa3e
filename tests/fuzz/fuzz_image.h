// Shared by the image harnesses (NIfTI, NRRD, DICOM, SEG, .inv3): the loader options they all use
// and the contract on what a loader returns.
#pragma once

#include <string>

#include "fuzz_support.h"
#include "volume/image_file.h"

namespace at::fuzz {

// Loader options with the fuzzing memory limit (kLoaderMaxBytes).
inline ImageLoadOptions loaderOptions() {
  ImageLoadOptions options;
  options.maxBytes = kLoaderMaxBytes;
  return options;
}

// Checks a loader's result — a one-line error starting with `path`, or an image with as many voxels
// as its dimensions say — and tells whether an image loaded.
inline bool checkLoaded(const Result<LoadedImage>& loaded, const std::string& path) {
  checkResult(loaded, path);
  if (!loaded) return false;
  expect(loaded->image.voxels.size() == loaded->image.dims().count(), "voxel count matches the dimensions");
  return true;
}

}  // namespace at::fuzz
