// What the structures of a known scan's labels are, for students: the catalogue
// data/segmentations/<scan>/structures.json gives each structure id its system, side, first-year
// description and review (what was checked on slices and in 3-D, and its state: "completed" when a
// first-year student would find nothing wrong, "flagged" with the reason in the text where the
// label is known to be off). The label map itself comes from
// scripts/label-scans.sh (`anatomy-tutor segment` from the kept seeds).
//
//   { "schema": 1, "dataset": "skull", "about": "...",
//     "structures": [ {"id": "mandible", "system": "teeth and jaws", "side": "midline",
//                      "description": "...", "review_state": "completed", "review": "..."} ] }
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
  std::string reviewState;  // completed | flagged
  std::string review;       // what was checked; for a flagged label, what is off
};

struct StructureCatalogue {
  std::string dataset;
  std::string about;        // how the labels were made and how far to trust them
  std::vector<CatalogueEntry> structures;
};

// Strict: unknown fields, wrong types, a side other than left/right/midline, a review_state other
// than completed/flagged or a repeated id are
// errors naming the file and the field.
Result<StructureCatalogue> loadStructureCatalogue(const std::filesystem::path& path);

// dataSubdirectory("segmentations")/<datasetId>/structures.json
std::filesystem::path catalogueFileFor(const std::string& datasetId);

// Gives the dataset's structures the catalogue's system and description (matched by id) and notes
// the catalogue's "about" in the provenance. Structures the catalogue lacks keep what they have.
void applyCatalogue(Dataset& dataset, const StructureCatalogue& catalogue);

}  // namespace at::app
