// Label names: a JSON object { "label value": "name" } through loadLabelNames.
#include "fuzz_support.h"
#include "volume/image_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace at;
  auto& scratch = fuzz::Scratch::instance();
  scratch.fresh();
  const auto path = scratch.write("labels.json", std::string_view(reinterpret_cast<const char*>(data), size)).string();
  fuzz::checkResult(loadLabelNames(path), path);
  return 0;
}
