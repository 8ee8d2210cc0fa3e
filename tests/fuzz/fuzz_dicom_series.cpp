// A DICOM series: the input's parts are the files slice0.dcm, slice1.dcm, … of one folder, loaded
// through loadImageFile as a folder (headers, grouping, stacking, every transfer syntax's decoder).
#include "fuzz_image.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  auto& scratch = fuzz::Scratch::instance();
  const auto& folder = scratch.fresh();
  const auto parts = fuzz::splitParts(data, size, 4);
  for (std::size_t i = 0; i < parts.size(); ++i) scratch.write("slice" + std::to_string(i) + ".dcm", parts[i]);
  auto loaded = loadImageFile(folder.string(), fuzz::loaderOptions());
  if (!fuzz::checkLoaded(loaded, folder.string())) return 0;
  fuzz::checkResult(toHuVolume(*loaded, folder.string()), folder.string());
  return 0;
}
