// NIfTI-1/-2 (.nii, and .nii.gz when the input is gzip data) through loadNifti, then the HU and
// label conversions a dataset applies to what it loads.
#include "fuzz_image.h"
#include "volume/nifti_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const bool gzip = size >= 2 && data[0] == 0x1f && data[1] == 0x8b;
  const std::string path = fuzz::inputAsFile(data, size, gzip ? "image.nii.gz" : "image.nii");
  auto loaded = loadNifti(path, fuzz::loaderOptions());
  if (!fuzz::checkLoaded(loaded, path)) return 0;
  fuzz::checkResult(toHuVolume(*loaded, path), path);
  fuzz::checkResult(toLabelMap(*loaded, path), path);
  return 0;
}
