// InVesalius 3 projects (.inv3) through loadInv3: the input is the archive (tar, gzip-compressed or
// plain) holding main.plist and the matrix it names.
#include "fuzz_image.h"
#include "volume/inv3_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string path = fuzz::inputAsFile(data, size, "project.inv3");
  fuzz::checkLoaded(loadInv3(path, fuzz::loaderOptions()), path);
  return 0;
}
