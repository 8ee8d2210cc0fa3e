// Label names: a JSON object { "label value": "name" } through loadLabelNames.
#include "fuzz_support.h"
#include "volume/image_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  const std::string path = fuzz::inputAsFile(data, size, "labels.json");
  fuzz::checkResult(loadLabelNames(path), path);
  return 0;
}
