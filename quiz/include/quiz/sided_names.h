// Typed names of paired structures: the side is graded apart from the name. A student who types
// "external acoustic meatus" has named the structure whatever its side; whether the side must be
// given is the question's (Question::askSide), never the spelling's. Typo tolerance is
// matchName's (quiz/name_matching.h), applied to the names without their side words, and a
// structure's counterpart on the other side never counts as "a closer structure".
#pragma once

#include <string>
#include <vector>

#include "quiz/name_matching.h"

namespace at::quiz {

// A name split into its side words and the rest: "Orbit (right)" → {"orbit", Right};
// "left right orbit" → {"orbit", None, true}. `body` is normalised (normalizeName).
struct SidedName {
  std::string body;
  Side side = Side::None;
  bool conflicting = false;  // both "left" and "right" were written
};
SidedName splitSide(const std::string& name);

// `name` without its side words, in its original letters: "Orbit (right)" → "Orbit",
// "Right maxillary antrum" → "Maxillary antrum". Brackets left empty are removed.
std::string withoutSide(const std::string& name);

// The side a structure belongs to, read off its display name when no catalogue says it.
Side sideOfName(const std::string& displayName);

// How a typed answer relates to one structure.
struct SidedMatch {
  bool nameAccepted = false;  // the name without its side matches the target (typos allowed)
  int distance = -1;          // edit distance to the closest side-free spelling of the target
  std::string matchedName;    // that spelling, as written in the catalogue
  Side typedSide = Side::None;
  bool sideConflicting = false;
  std::string closerStructure;  // another structure (not the target's counterpart) as close or closer
};

// Matches `typed` against `target`'s names with side words removed; other entries of `catalog`
// whose side-free names equal one of the target's (its counterpart on the other side) are not
// competitors.
SidedMatch matchSidedName(const std::string& typed, const NameEntry& target, const NameCatalog& catalog);

}  // namespace at::quiz
