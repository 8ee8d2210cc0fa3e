// InVesalius 3 projects (.inv3) through loadInv3: the input is the archive (tar, gzip-compressed or
// plain) holding main.plist and the matrix it names.
#include "fuzz_support.h"
#include "volume/image_file.h"
#include "volume/inv3_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  auto& scratch = fuzz::Scratch::instance();
  scratch.fresh();
  const auto path = scratch.write("project.inv3", std::string_view(reinterpret_cast<const char*>(data), size)).string();
  ImageLoadOptions options;
  options.maxBytes = fuzz::kLoaderMaxBytes;
  auto loaded = loadInv3(path, options);
  fuzz::checkResult(loaded, path);
  if (!loaded) return 0;
  fuzz::expect(loaded->image.voxels.size() == loaded->image.dims().count(), "voxel count matches the dimensions");
  return 0;
}
