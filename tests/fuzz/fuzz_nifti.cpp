// NIfTI-1/-2 (.nii, and .nii.gz when the input is gzip data) through loadNifti, then the HU and
// label conversions a dataset applies to what it loads.
#include "fuzz_support.h"
#include "volume/image_file.h"
#include "volume/nifti_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  auto& scratch = fuzz::Scratch::instance();
  scratch.fresh();
  const bool gzip = size >= 2 && data[0] == 0x1f && data[1] == 0x8b;
  const auto path = scratch.write(gzip ? "image.nii.gz" : "image.nii",
                                  std::string_view(reinterpret_cast<const char*>(data), size)).string();
  ImageLoadOptions options;
  options.maxBytes = fuzz::kLoaderMaxBytes;
  auto loaded = loadNifti(path, options);
  fuzz::checkResult(loaded, path);
  if (!loaded) return 0;
  fuzz::expect(loaded->image.voxels.size() == loaded->image.dims().count(), "voxel count matches the dimensions");
  fuzz::checkResult(toHuVolume(*loaded, path), path);
  fuzz::checkResult(toLabelMap(*loaded, path), path);
  return 0;
}
