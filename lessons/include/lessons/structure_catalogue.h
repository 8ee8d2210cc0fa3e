// The structure catalogue of a dataset: what each labelled structure is called — its name without
// a side, the patient's side it belongs to, synonyms and Latin (Terminologia Anatomica) names, and
// the system it belongs to. Every course on the dataset grades typed names with it
// (lessons::gradingContext), so a course need not repeat them. The shipped catalogues are the files
// data/catalogues/<dataset>.json, compiled into the library (data/catalogues/README.md).
#pragma once

#include <string>
#include <vector>

#include "core/error.h"
#include "quiz/name_matching.h"

namespace at::lessons {

struct CatalogueEntry {
  std::string structureId;
  std::string name;                    // without the side: "External acoustic meatus"
  quiz::Side side = quiz::Side::None;  // the patient's side; None for midline/unpaired structures
  std::vector<std::string> synonyms;   // English names, without a side
  std::vector<std::string> latin;      // Latin / TA names, without a side
  std::string system;                  // "ear and temporal bone", "inner ear", …
};

struct StructureCatalogue {
  std::string datasetId;
  std::string title;
  std::vector<CatalogueEntry> entries;

  const CatalogueEntry* find(const std::string& structureId) const;
};

// Strict reading, like a course: unknown fields, wrong types, a side other than "left"/"right", a
// name or synonym that carries a side word, duplicate ids are errors naming the field by its path
// ("skull.json: structures[3].side: must be \"left\" or \"right\"").
Result<StructureCatalogue> parseStructureCatalogue(const std::string& text, const std::string& sourceName);

// The shipped catalogue of a dataset id, or nullptr when none is shipped (an imported dataset:
// grading then reads sides off the display names). Parsed once; a shipped file that does not
// parse is a build error caught by the tests (tests/lessons/test_structure_catalogue.cpp).
const StructureCatalogue* shippedCatalogue(const std::string& datasetId);
// Every shipped catalogue, in file-name order.
const std::vector<StructureCatalogue>& shippedCatalogues();

}  // namespace at::lessons
