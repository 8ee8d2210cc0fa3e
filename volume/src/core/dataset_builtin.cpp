// Built-in datasets by name: "phantom" (256³) and "phantom:N" (N³, the same anatomy in mm).
#include <cctype>
#include <string>

#include "volume/dataset_source.h"
#include "volume/phantom.h"

namespace at {

namespace {
constexpr int kMinPhantomSize = 16;
constexpr int kMaxPhantomSize = 1024;
const std::string kPhantomName = "phantom";
}  // namespace

bool isBuiltinDatasetName(const std::string& name) {
  return name == kPhantomName || name.rfind(kPhantomName + ":", 0) == 0;
}

Result<Dataset> openBuiltinDataset(const std::string& name) {
  if (!isBuiltinDatasetName(name))
    return fail("unknown dataset '" + name + "' (built-in datasets: phantom, phantom:N)");
  PhantomOptions options;
  if (name != kPhantomName) {
    const std::string sizeText = name.substr(kPhantomName.size() + 1);
    bool digits = !sizeText.empty() && sizeText.size() <= 5;
    for (char c : sizeText) digits = digits && std::isdigit(static_cast<unsigned char>(c));
    const int size = digits ? std::stoi(sizeText) : -1;
    if (size < kMinPhantomSize || size > kMaxPhantomSize)
      return fail("dataset '" + name + "': the phantom size must be a whole number from " +
                  std::to_string(kMinPhantomSize) + " to " + std::to_string(kMaxPhantomSize) +
                  " (e.g. phantom:128)");
    options.size = size;
  }
  Dataset phantom = makePhantom(options);
  phantom.intensity.reason = "synthetic phantom in HU";
  return phantom;
}

}  // namespace at
