// The forms the importers give a dataset's species, modality and structures (str::identifier, displayNameOf
// of printableText), held against those from a course package, which never went through them.
#pragma once

#include <cstddef>
#include <string>

namespace at {

// A species: lower-case letters, '-' and '_' ("human", "dog").
bool isValidSpecies(const std::string& species);
// A structure id: 1 … 100 of a-z, 0-9 and '_'.
bool isValidStructureId(const std::string& id);
// A name or system: one printable line (printableText leaves it as it is) of at most `maxBytes`
// (a package allows 600: the 120 characters and "…" an import keeps, of up to 4 bytes each).
bool isPrintableLine(const std::string& text, std::size_t maxBytes);
// A description: printable lines (printableLines leaves them as they are) of at most `maxBytes`.
bool isPrintableLines(const std::string& text, std::size_t maxBytes);
// A DICOM Modality as the tag holds it (a code string: "CT", "MR", "PT"): 1 … 16 of A-Z, 0-9, '_'
// and ' ', not starting with ' '.
bool isDicomModalityCode(const std::string& code);

}  // namespace at
