// Typed-name matching for Name questions: tolerant to case, accents, spacing, punctuation, the
// place of "left"/"right", listed synonyms and small typos — but a typo never counts when the text
// is at least as close to a different structure's name or synonym.
#pragma once

#include <string>
#include <vector>

namespace at::quiz {

// Canonical form for comparison: UTF-8 Latin letters folded to ASCII lower case (é→e, ß→ss,
// æ→ae …), punctuation and hyphens turned into spaces, runs of space collapsed, and the words
// "left"/"right" (and "l"/"r" abbreviations as whole words) moved to the end, the articles
// "the", "a", "an" dropped: "The Semicircular-Canal, LEFT lateral" → "semicircular canal lateral left".
std::string normalizeName(const std::string& text);

// A structure's display name as it reads inside a sentence ("Click the cochlea."): names are
// stored in label case, their first letter capitalised ("Cochlea", "Superior semicircular canal"),
// so the first letter is lower-cased — unless the first word is an abbreviation or a proper name:
// it has a digit or another capital ("C1", "CN VII", "IAC"), ends in a possessive ("Meckel's
// cave", "Prussak’s space"), or is an eponym of kEponymousWords ("Eustachian tube", "Sylvian
// fissure"). The rest of the name is kept as written.
std::string nameInSentence(const std::string& displayName);

// Optimal string alignment (restricted Damerau–Levenshtein) distance on bytes: insertions,
// deletions, substitutions and transpositions of adjacent characters each cost 1.
int damerauLevenshtein(const std::string& a, const std::string& b);

// Edit distance accepted as a typo for a name of normalised length n: 0 up to 4 characters,
// 1 up to 8, 2 up to 16, 3 beyond.
int typoAllowance(std::size_t normalizedLength);

// The patient's side a structure belongs to; None for midline or unpaired structures.
enum class Side { None, Left, Right };
const char* toString(Side side);  // "", "left", "right"

// Every accepted spelling of one structure.
struct NameEntry {
  std::string structureId;
  std::vector<std::string> names;  // display name, the id with '_' as spaces, synonyms
  // From the dataset's structure catalogue (lessons/structure_catalogue.h), or read off the
  // display name ("Orbit (right)" → Right, "Orbit") when the dataset has none. Names in `names`
  // may carry the side as a word; grading compares them without it (quiz/sided_names.h).
  Side side = Side::None;
  std::string baseName;            // the display name without its side; "" = names.front()
};

// All structures a student could mean (the dataset's structures with course synonyms).
using NameCatalog = std::vector<NameEntry>;

struct NameMatch {
  bool accepted = false;
  int distance = -1;             // edit distance to the closest accepted spelling of the target
  std::string matchedName;       // that spelling
  std::string closerStructure;   // set when another structure's name is as close or closer
  std::string closerName;
};

// Matches `typed` against `targetNames` (the target's spellings). Exact after normalisation →
// accepted. Otherwise accepted when the distance to the closest target spelling is within
// typoAllowance of that spelling's normalised length, unless some entry of `catalog` for a structure other than `targetId` is
// at the same or a smaller distance (then `closerStructure` names it).
NameMatch matchName(const std::string& typed, const std::string& targetId,
                    const std::vector<std::string>& targetNames, const NameCatalog& catalog);

}  // namespace at::quiz
