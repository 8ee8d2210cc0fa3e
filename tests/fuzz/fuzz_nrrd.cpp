// NRRD with an attached header (.nrrd): the whole input is the file; raw and gzip data, 3D Slicer
// segment keys. A header that names data files finds none beside it.
#include "fuzz_image.h"
#include "volume/nrrd_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string path = fuzz::inputAsFile(data, size, "image.nrrd");
  auto loaded = loadNrrd(path, fuzz::loaderOptions());
  if (!fuzz::checkLoaded(loaded, path)) return 0;
  fuzz::checkResult(toLabelMap(*loaded, path), path);
  return 0;
}
