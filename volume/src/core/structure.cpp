#include "volume/structure.h"

#include <algorithm>
#include <cctype>

namespace at {

namespace {
std::string lowered(const std::string& s) {
  std::string out = s;
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return std::tolower(c); });
  return out;
}
}  // namespace

const Structure* Dataset::findStructure(const std::string& idOrName) const {
  for (const Structure& s : structures)
    if (s.id == idOrName) return &s;
  const std::string wanted = lowered(idOrName);
  for (const Structure& s : structures)
    if (lowered(s.displayName) == wanted || lowered(s.id) == wanted) return &s;
  return nullptr;
}

const Structure* Dataset::findStructureByLabel(std::uint16_t label) const {
  for (const Structure& s : structures)
    if (s.label == label) return &s;
  return nullptr;
}

}  // namespace at
