// What the structures of a known scan's labels are, for students: the catalogue
// data/segmentations/<scan>/structures.json gives each structure id its system, side, first-year
// description and review state (how the label was checked). The label map itself comes from
// scripts/label-scans.sh (`anatomy-tutor segment` from the kept seeds).
//
//   { "schema": 1, "dataset": "skull", "about": "...",
//     "structures": [ {"id": "mandible", "system": "teeth and jaws", "side": "midline",
//                      "description": "...", "review": "..."} ] }
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "core/error.h"
#include "volume/structure.h"

namespace at::app {

struct CatalogueEntry {
  std::string id;
  std::string system;
  std::string side;         // left | right | midline
  std::string description;
  std::string review;
};

struct StructureCatalogue {
  std::string dataset;
  std::string about;        // how the labels were made and how far to trust them
  std::vector<CatalogueEntry> structures;
};

// Strict: unknown fields, wrong types, a side other than left/right/midline or a repeated id are
// errors naming the file and the field.
Result<StructureCatalogue> loadStructureCatalogue(const std::filesystem::path& path);

// dataSubdirectory("segmentations")/<datasetId>/structures.json
std::filesystem::path catalogueFileFor(const std::string& datasetId);

// Gives the dataset's structures the catalogue's system and description (matched by id) and notes
// the catalogue's "about" in the provenance. Structures the catalogue lacks keep what they have.
void applyCatalogue(Dataset& dataset, const StructureCatalogue& catalogue);

}  // namespace at::app
