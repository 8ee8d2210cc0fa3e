#include "volume/structure.h"
#include "volume/structure_forms.h"

#include <algorithm>
#include <cctype>
#include <cmath>

#include "core/printable_text.h"
#include "core/strings.h"

namespace at {

bool isValidSpecies(const std::string& species) {
  return !species.empty() && std::all_of(species.begin(), species.end(), [](unsigned char c) {
    return (c >= 'a' && c <= 'z') || c == '-' || c == '_';
  });
}

bool isValidStructureId(const std::string& id) {
  return !id.empty() && id.size() <= 100 && std::all_of(id.begin(), id.end(), [](unsigned char c) {
    return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_';
  });
}

bool isPrintableLine(const std::string& text, std::size_t maxBytes) {
  return text.size() <= maxBytes && printableText(text, text.size() + 1) == text;
}

bool isPrintableLines(const std::string& text, std::size_t maxBytes) {
  return text.size() <= maxBytes && printableLines(text) == text;
}

bool isDicomModalityCode(const std::string& code) {
  return !code.empty() && code.size() <= 16 && code[0] != ' ' && std::all_of(code.begin(), code.end(), [](unsigned char c) {
    return (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == ' ';
  });
}

std::string displayNameOf(const std::string& name) {
  std::string out = name;
  std::replace(out.begin(), out.end(), '_', ' ');
  if (!out.empty()) out[0] = char(std::toupper(static_cast<unsigned char>(out[0])));
  return out;
}

std::array<float, 3> paletteColour(std::uint16_t label) {
  const double hue = std::fmod(label * 137.508, 360.0) / 60.0;
  const double x = 1 - std::abs(std::fmod(hue, 2.0) - 1);
  double r = 0, g = 0, b = 0;
  switch (int(hue)) {
    case 0: r = 1, g = x; break;
    case 1: r = x, g = 1; break;
    case 2: g = 1, b = x; break;
    case 3: g = x, b = 1; break;
    case 4: r = x, b = 1; break;
    default: r = 1, b = x; break;
  }
  auto mix = [](double c) { return float(std::pow(0.25 + 0.7 * c, 2.2)); };
  return {mix(r), mix(g), mix(b)};
}

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
