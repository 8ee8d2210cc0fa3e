// Question kinds, answers and grades (ARCHITECTURE.md §5). Plain structs: db/ stores them, lessons/
// sequences them, the app shows them. A `Question` is what a course author writes; keys that depend
// on the dataset (relation, order, identify distractors) are computed from it into a
// `ResolvedQuestion` (quiz/keys.h) and never written by hand.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "volume/geometry.h"

namespace at::quiz {

enum class QuestionKind {
  Locate,    // click the structure in the 3-D view
  Identify,  // multiple choice on a highlighted structure
  Name,      // type the name of a highlighted structure
  Relation,  // which candidate is nearest to / reachable from a structure (by WDT distance)
  Order,     // the structures met along a straight drilling path, in order
};

const char* toString(QuestionKind kind);  // "locate", "identify", "name", "relation", "order"
Result<QuestionKind> parseQuestionKind(const std::string& text);

enum class RelationKind {
  Nearest,    // the candidate with the smallest weighted distance from `from`
  Reachable,  // the only candidate whose weighted distance from `from` is <= thresholdMm
};

const char* toString(RelationKind kind);  // "nearest", "reachable"
Result<RelationKind> parseRelationKind(const std::string& text);

// Relation question: "which of `candidates` is nearest to / reachable from `from`".
struct RelationSpec {
  std::string from;                     // structure id the distances are measured from
  RelationKind kind = RelationKind::Nearest;
  std::vector<std::string> candidates;  // structure ids offered as choices, in display order
  double thresholdMm = 0;               // Reachable: weighted-distance bound (> 0)
};

// Order question: a straight path from entry to target. Each end is either a point in patient
// LPS millimetres or a structure id (its centroid). Exactly one of the two forms per end.
struct OrderSpec {
  std::optional<Vec3> entryMm;
  std::optional<Vec3> targetMm;
  std::string entryStructure;
  std::string targetStructure;
  int extraChoices = 2;  // structures not on the path added to the offered list (nearest ones)
};

struct Question {
  std::string id;                   // unique across all courses: "<lesson id>.<short name>"
  QuestionKind kind = QuestionKind::Locate;
  std::string prompt;               // shown to the student
  // The structure the question trains: progress and review are recorded under it.
  // Locate/identify/name: the structure asked about. Relation: normally relation.from.
  // Order: normally the drilling target.
  std::string target;
  double toleranceMm = 0;           // Locate: a click this weighted distance from the target or
                                    // closer is correct (small structures); 0 = must hit it
  std::vector<std::string> choices; // Identify: structure ids offered (must contain target);
                                    // empty = computed: target + the `distractors` nearest by WDT
  int distractors = 3;              // Identify with computed choices
  std::vector<std::string> synonyms;  // Name: accepted besides the display name and course synonyms
  bool askSide = false;             // Name: the prompt asks for the patient's side of a paired
                                    // structure; a name without it earns partial credit
  RelationSpec relation;            // Relation only
  OrderSpec order;                  // Order only
  double difficulty = 1500;         // initial Elo difficulty (same scale as ability, 1500 = average)
  std::string explanation;          // shown with the feedback, whatever the answer
};

// A question ready to ask: dataset-dependent parts computed (quiz/keys.h).
struct ResolvedQuestion {
  Question question;
  std::vector<std::string> choices;   // Identify/Relation: structure ids in display order;
                                      // Order: structure ids offered to arrange (shuffled)
  int keyChoice = -1;                 // Identify/Relation: index into choices
  std::vector<std::string> keyOrder;  // Order: structure ids met along the path, in order
};

// A click in the 3-D view: the structure under the cursor ("" for none) and the weighted
// distance in mm from the question's target to the clicked point (the app samples the target's
// WDT field there; negative or NaN = unknown).
struct Pick {
  std::string structure;
  double distanceMm = -1;
  // The pixel (x, y) clicked, when the pick is judged elsewhere (a class server grades a locate
  // item from the pixel on its picture; structure and distance then stay unset).
  std::optional<std::array<int, 2>> pixel;
  // With a pixel picked on a fixed view (a lesson's question picture): that view's id, from which
  // a class server grades the pixel (TerminalViews::lastViewId); empty otherwise.
  std::string view;
};

// A student's answer; exactly the member for the question's kind is set.
struct Answer {
  std::optional<int> choice;                     // Identify, Relation: index into choices
  std::optional<std::string> text;               // Name
  std::optional<Pick> pick;                      // Locate
  std::optional<std::vector<std::string>> order; // Order: structure ids (names accepted too)
};

struct Grade {
  bool correct = false;
  double score = 0;      // 0..1; partial credit for Order, and for Name questions that ask for
                         // the side (0.5 without a side, 0.25 with the wrong one)
  std::string feedback;  // one or two sentences for the student
};

}  // namespace at::quiz
