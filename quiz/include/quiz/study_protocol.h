// Preference studies like the paper's survey (its Table 2): for each structure a participant
// compares two conditions — condition 0 the WDT rendering preset, condition 1 the bare-structure
// preset — shown blinded as "A" and "B", and rates items on a 1–5 scale (1 = prefer A … 5 =
// prefer B as shown). Ratings are stored as shown and unblinded onto the paper's scale
// (1 = prefer WDT … 5 = prefer bare) with the stored A/B mapping.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "core/error.h"

namespace at::quiz {

struct StudyCondition {
  std::string id;          // "wdt", "bare"
  std::string label;       // for coordinators only; never shown to participants
  std::string presetSuffix;  // preset id = structure id + suffix unless `presets` overrides
  bool operator==(const StudyCondition&) const = default;
};

struct StudyItem {
  std::string id;          // "shape", "context", "localization", "utility"
  std::string wording;     // question shown to participants
  bool operator==(const StudyItem&) const = default;
};

struct StudyScale {
  int min = 1, max = 5;
  std::map<int, std::string> anchors;  // value → anchor text as shown (in A/B terms)
  int midpoint() const { return (min + max) / 2; }
  bool operator==(const StudyScale&) const = default;
};

struct StudyProtocol {
  int schema = 1;
  std::string id;          // stable id ("wdt_vs_bare_phantom")
  std::string title;
  std::string dataset;     // "phantom"
  std::vector<std::string> structures;             // structure ids, in definition order
  std::vector<StudyCondition> conditions;          // exactly two: [0] WDT, [1] bare
  std::map<std::string, std::vector<std::string>> presets;  // structure → preset id per condition
  std::vector<StudyItem> items;
  StudyScale scale;
  std::vector<std::string> groups;                 // participant groups ("non-medical", "medical")
  std::uint64_t seed = 1;                          // counterbalancing seed (stored)
  double t = 0.5;          // render parameters shown with both conditions (recorded per response)

  // Preset id of `condition` (0 or 1) for `structure`.
  std::string presetFor(const std::string& structure, int condition) const;
  bool operator==(const StudyProtocol&) const = default;
};

// Parses a study definition strictly: unknown or ill-typed fields are errors naming the field
// ("paper_survey.json: field 'items[2].wording' must be a string").
Result<StudyProtocol> parseStudyProtocol(const std::string& jsonText, const std::string& sourceName);
Result<StudyProtocol> loadStudyProtocol(const std::string& path);
// Serialises losslessly (parse(serialise(p)) == p).
std::string serialiseStudyProtocol(const StudyProtocol& protocol);

// Maps a rating as shown (1 = prefer A … 5 = prefer B) onto the paper's scale (1 = prefer
// condition 0 / WDT … 5 = prefer condition 1 / bare), given whether condition 0 was shown as A.
int unblindRating(int ratingAsShown, bool aIsFirstCondition, const StudyScale& scale);

// Participant ids are pseudonyms: 1 to 64 letters, digits, '_' or '-', starting with a letter or a
// digit, so that they are valid REDCap record names and safe in every export.
Status validParticipantId(const std::string& id);

}  // namespace at::quiz
