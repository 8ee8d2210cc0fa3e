#include "volume/structure.h"

#include <algorithm>
#include <cctype>

#include "core/strings.h"

namespace at {

const Structure* Dataset::findStructure(const std::string& idOrName) const {
  for (const Structure& s : structures)
    if (s.id == idOrName) return &s;
  const std::string wanted = str::lower(idOrName);
  for (const Structure& s : structures)
    if (str::lower(s.displayName) == wanted || str::lower(s.id) == wanted) return &s;
  return nullptr;
}

const Structure* Dataset::findStructureByLabel(std::uint16_t label) const {
  for (const Structure& s : structures)
    if (s.label == label) return &s;
  return nullptr;
}

}  // namespace at
