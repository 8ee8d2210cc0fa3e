// NRRD with an attached header (.nrrd): the whole input is the file; raw and gzip data, 3D Slicer
// segment keys. A header that names data files finds none beside it.
#include "fuzz_support.h"
#include "volume/image_file.h"
#include "volume/nrrd_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  auto& scratch = fuzz::Scratch::instance();
  scratch.fresh();
  const auto path = scratch.write("image.nrrd", std::string_view(reinterpret_cast<const char*>(data), size)).string();
  ImageLoadOptions options;
  options.maxBytes = fuzz::kLoaderMaxBytes;
  auto loaded = loadNrrd(path, options);
  fuzz::checkResult(loaded, path);
  if (!loaded) return 0;
  fuzz::expect(loaded->image.voxels.size() == loaded->image.dims().count(), "voxel count matches the dimensions");
  fuzz::checkResult(toLabelMap(*loaded, path), path);
  return 0;
}
