// Grading of every question kind. Grading is pure: the caller records the result (lessons/).
// An answer that does not fit the question (wrong member set, choice out of range) is an Error,
// not a wrong answer, so that `play --answers` can report the bad line.
#pragma once

#include <string>
#include <vector>

#include "quiz/name_matching.h"
#include "quiz/question.h"
#include "core/error.h"

namespace at::quiz {

// What grading needs beyond the question: every structure's accepted names (Name questions,
// and Order answers given as names) and display names for feedback.
struct GradingContext {
  NameCatalog names;
  // Display name of a structure id (the first entry of its NameEntry), or the id itself.
  std::string displayName(const std::string& structureId) const;
  // The display name as it reads inside a sentence (nameInSentence: "the cochlea", "the C1").
  std::string nameInSentence(const std::string& structureId) const;
  // The display name without the structure's side ("External acoustic meatus"): feedback on a
  // question that does not ask for the side uses it, so a side is never presented as the error.
  std::string baseName(const std::string& structureId) const;
  // The entry of a structure id, or nullptr.
  const NameEntry* entry(const std::string& structureId) const;
  // The structure's side: its entry's, else read off its display name.
  Side side(const std::string& structureId) const;
};

// Dispatches on question.question.kind.
Result<Grade> grade(const ResolvedQuestion& question, const Answer& answer, const GradingContext& context);

// Locate: correct when the picked structure is the target, or when question.toleranceMm > 0 and
// 0 <= pick.distanceMm <= toleranceMm (the boundary counts).
Result<Grade> gradeLocate(const ResolvedQuestion& question, const Pick& pick, const GradingContext& context);
// Identify and Relation: correct when the choice is keyChoice.
Result<Grade> gradeChoice(const ResolvedQuestion& question, int choice, const GradingContext& context);
// Name: matchSidedName (quiz/sided_names.h) against the target's names (catalog entry + question
// synonyms) without their side words. The side is graded only when question.askSide and the
// target has one: none given → score 0.5 with a "which side?" hint, the other side → 0.25, both
// not correct. Otherwise a name without a side (or with a side nobody asked for) is correct and
// the feedback names the structure without its side.
Result<Grade> gradeName(const ResolvedQuestion& question, const std::string& text, const GradingContext& context);
// Order: correct when the sequence equals keyOrder; otherwise score = LCS(answer, key) /
// max(|answer|, |key|) (structures listed that the path does not meet cost like missing ones).
// Entries may be structure ids or names (resolved through the catalog, exact after normalisation).
Result<Grade> gradeOrder(const ResolvedQuestion& question, const std::vector<std::string>& order,
                         const GradingContext& context);

// Length of the longest common subsequence.
std::size_t longestCommonSubsequence(const std::vector<std::string>& a, const std::vector<std::string>& b);

}  // namespace at::quiz
