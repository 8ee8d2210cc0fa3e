// NRRD with a detached header: part 1 of the input is image.nhdr, the following parts are the data
// files data1.raw, data2.raw, … beside it, and part 2 is also data.raw (the seeds name them with
// `data file: data.raw`, `data file: data%d.raw 1 N 1` and `data file: LIST`).
#include "fuzz_image.h"
#include "volume/nrrd_io.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  auto& scratch = fuzz::Scratch::instance();
  scratch.fresh();
  const auto parts = fuzz::splitParts(data, size, 5);
  const auto path = scratch.write("image.nhdr", parts[0]).string();
  for (std::size_t i = 1; i < parts.size(); ++i) scratch.write("data" + std::to_string(i) + ".raw", parts[i]);
  if (parts.size() > 1) scratch.write("data.raw", parts[1]);
  fuzz::checkLoaded(loadNrrd(path, fuzz::loaderOptions()), path);
  return 0;
}
