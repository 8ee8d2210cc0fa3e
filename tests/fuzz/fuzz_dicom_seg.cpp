// DICOM SEG (binary Segmentation Storage) through loadDicomSeg: the input is one .dcm file.
#include "fuzz_support.h"
#include "volume/dicom_seg.h"
#include "volume/image_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  auto& scratch = fuzz::Scratch::instance();
  scratch.fresh();
  const auto path = scratch.write("seg.dcm", std::string_view(reinterpret_cast<const char*>(data), size)).string();
  ImageLoadOptions options;
  options.maxBytes = fuzz::kLoaderMaxBytes;
  auto loaded = loadDicomSeg(path, options);
  fuzz::checkResult(loaded, path);
  if (!loaded) return 0;
  fuzz::expect(loaded->image.voxels.size() == loaded->image.dims().count(), "voxel count matches the dimensions");
  fuzz::checkResult(toLabelMap(*loaded, path), path);
  return 0;
}
