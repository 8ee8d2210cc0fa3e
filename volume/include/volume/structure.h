// Anatomical structures of a dataset and the dataset itself.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "volume/grid.h"
#include "volume/intensity.h"

namespace at {

struct Structure {
  std::uint16_t label = 0;          // value in the LabelMap
  std::string id;                   // stable snake_case id: "cochlea", "lateral_semicircular_canal"
  std::string displayName;          // "Lateral semicircular canal"
  std::array<float, 3> colour{1, 1, 1};  // linear RGB 0..1
  std::string system;               // group for browsing: "inner ear", "nerves", "vessels", …
  std::string description;          // one or two sentences for students
};

// Where a dataset came from. Never holds patient identifiers (no names, IDs, dates, institutions).
struct Provenance {
  std::string source;               // "synthetic phantom (seed 1, 256^3)" or a file path
  std::string labelsSource;         // label file path, or empty
  std::vector<std::string> notes;   // loader remarks: chosen series, resampling, …
  std::vector<std::string> warnings;  // one line each, naming the file: what the user should check
};

// How names given by users and label-name files are shown: "kidney_right" → "Kidney right";
// names with spaces or capitals are kept as written.
std::string displayNameOf(const std::string& name);
// A distinct colour for a label that has none (linear RGB): hues spaced by the golden angle.
std::array<float, 3> paletteColour(std::uint16_t label);

struct Dataset {
  std::string id;                   // "phantom" or an imported dataset's name
  std::string displayName;
  std::string species = "human";
  Volume volume;                    // stored values: HU for CT, else plain intensities (see intensity)
  IntensityModel intensity;         // what the stored values mean, their window
  LabelMap labels;                  // same Geometry as volume
  std::vector<Structure> structures;
  Provenance provenance;

  const Structure* findStructure(const std::string& idOrName) const;
  const Structure* findStructureByLabel(std::uint16_t label) const;
};

}  // namespace at
