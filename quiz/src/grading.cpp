#include "quiz/grading.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace at::quiz {
namespace {

// Float32 distance fields round 0.3 mm to 0.30000001: a click exactly at the boundary must count.
constexpr double kToleranceSlackMm = 1e-6;

Grade makeGrade(bool correct, double score, std::string feedback, const Question& question) {
  if (!question.explanation.empty()) feedback += " " + question.explanation;
  return Grade{correct, score, std::move(feedback)};
}

std::string formatMm(double mm) {
  std::ostringstream out;
  out.precision(mm < 10 ? 2 : 3);
  out << mm << " mm";
  return out.str();
}

// Resolves an order entry given as id or name to a structure id ("" if unknown).
std::string resolveStructure(const std::string& entry, const GradingContext& context) {
  for (const NameEntry& e : context.names) {
    if (e.structureId == entry) return e.structureId;
  }
  const std::string normal = normalizeName(entry);
  for (const NameEntry& e : context.names) {
    if (normalizeName(e.structureId) == normal) return e.structureId;
    for (const std::string& name : e.names) {
      if (normalizeName(name) == normal) return e.structureId;
    }
  }
  return "";
}

std::string joinNames(const std::vector<std::string>& ids, const GradingContext& context) {
  std::string out;
  for (const std::string& id : ids) {
    if (!out.empty()) out += " → ";
    out += context.nameInSentence(id);
  }
  return out;
}

}  // namespace

std::string GradingContext::displayName(const std::string& structureId) const {
  for (const NameEntry& entry : names) {
    if (entry.structureId == structureId && !entry.names.empty()) return entry.names.front();
  }
  return structureId;
}

std::string GradingContext::nameInSentence(const std::string& structureId) const {
  return quiz::nameInSentence(displayName(structureId));
}

Result<Grade> grade(const ResolvedQuestion& question, const Answer& answer, const GradingContext& context) {
  const Question& q = question.question;
  const int given = int(answer.choice.has_value()) + int(answer.text.has_value()) + int(answer.pick.has_value()) +
                    int(answer.order.has_value());
  if (given != 1) {
    return fail("question " + q.id + ": an answer needs exactly one of choice, text, pick or order");
  }
  const auto wrongForm = [&](const char* expected) {
    return fail("question " + q.id + " (" + toString(q.kind) + ") needs " + expected);
  };
  switch (q.kind) {
    case QuestionKind::Locate:
      if (!answer.pick) return wrongForm("a pick (\"pick\": structure, \"distance_mm\")");
      return gradeLocate(question, *answer.pick, context);
    case QuestionKind::Identify:
    case QuestionKind::Relation:
      if (!answer.choice) return wrongForm("a choice (\"choice\": index)");
      return gradeChoice(question, *answer.choice, context);
    case QuestionKind::Name:
      if (!answer.text) return wrongForm("a typed name (\"text\")");
      return gradeName(question, *answer.text, context);
    case QuestionKind::Order:
      if (!answer.order) return wrongForm("an order (\"order\": [structures])");
      return gradeOrder(question, *answer.order, context);
  }
  return fail("question " + q.id + ": unknown kind");
}

Result<Grade> gradeLocate(const ResolvedQuestion& question, const Pick& pick, const GradingContext& context) {
  const Question& q = question.question;
  const std::string target = context.nameInSentence(q.target);
  if (pick.structure == q.target) {
    return makeGrade(true, 1, "Correct: that is the " + target + ".", q);
  }
  const bool distanceKnown = std::isfinite(pick.distanceMm) && pick.distanceMm >= 0;
  if (q.toleranceMm > 0 && distanceKnown && pick.distanceMm <= q.toleranceMm + kToleranceSlackMm) {
    return makeGrade(true, 1,
                     "Correct: your click was " + formatMm(pick.distanceMm) + " from the " + target +
                         " (accepted within " + formatMm(q.toleranceMm) + " for a structure this small).",
                     q);
  }
  std::string feedback = pick.structure.empty()
                             ? "Not quite: you clicked on no labelled structure."
                             : "Not quite: you clicked the " + context.nameInSentence(pick.structure) + ".";
  if (distanceKnown) feedback += " The " + target + " was " + formatMm(pick.distanceMm) + " away.";
  return makeGrade(false, 0, feedback, q);
}

Result<Grade> gradeChoice(const ResolvedQuestion& question, int choice, const GradingContext& context) {
  const Question& q = question.question;
  if (question.keyChoice < 0 || question.keyChoice >= int(question.choices.size())) {
    return fail("question " + q.id + ": has no computed key (resolve it first)");
  }
  if (choice < 0 || choice >= int(question.choices.size())) {
    return fail("question " + q.id + ": choice " + std::to_string(choice) + " is out of range 0.." +
                std::to_string(question.choices.size() - 1));
  }
  const std::string key = context.displayName(question.choices[question.keyChoice]);
  if (choice == question.keyChoice) return makeGrade(true, 1, "Correct: " + key + ".", q);
  return makeGrade(false, 0,
                   "Not quite: you chose the " + context.nameInSentence(question.choices[choice]) +
                       "; the answer is the " + context.nameInSentence(question.choices[question.keyChoice]) + ".",
                   q);
}

Result<Grade> gradeName(const ResolvedQuestion& question, const std::string& text, const GradingContext& context) {
  const Question& q = question.question;
  std::vector<std::string> names;
  for (const NameEntry& entry : context.names) {
    if (entry.structureId == q.target) names = entry.names;
  }
  if (names.empty()) names.push_back(q.target);
  names.insert(names.end(), q.synonyms.begin(), q.synonyms.end());
  const std::string target = context.displayName(q.target);
  const std::string targetInSentence = context.nameInSentence(q.target);
  const NameMatch match = matchName(text, q.target, names, context.names);
  if (match.accepted && match.distance == 0) return makeGrade(true, 1, "Correct: " + target + ".", q);
  if (match.accepted) {
    return makeGrade(true, 1, "Correct (mind the spelling): " + match.matchedName + ".", q);
  }
  if (!match.closerStructure.empty()) {
    return makeGrade(false, 0,
                     "Not quite: \"" + text + "\" reads as the " + context.nameInSentence(match.closerStructure) +
                         "; this is the " + targetInSentence + ".",
                     q);
  }
  return makeGrade(false, 0, "Not quite: this is the " + targetInSentence + ".", q);
}

std::size_t longestCommonSubsequence(const std::vector<std::string>& a, const std::vector<std::string>& b) {
  std::vector<std::vector<std::size_t>> t(a.size() + 1, std::vector<std::size_t>(b.size() + 1, 0));
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      t[i][j] = a[i - 1] == b[j - 1] ? t[i - 1][j - 1] + 1 : std::max(t[i - 1][j], t[i][j - 1]);
    }
  }
  return t[a.size()][b.size()];
}

Result<Grade> gradeOrder(const ResolvedQuestion& question, const std::vector<std::string>& order,
                         const GradingContext& context) {
  const Question& q = question.question;
  if (question.keyOrder.empty()) return fail("question " + q.id + ": has no computed key (resolve it first)");
  std::vector<std::string> ids;
  for (const std::string& entry : order) {
    const std::string id = resolveStructure(entry, context);
    if (id.empty()) return fail("question " + q.id + ": order: unknown structure '" + entry + "'");
    ids.push_back(id);
  }
  const std::string path = "The path meets: " + joinNames(question.keyOrder, context) + ".";
  if (ids == question.keyOrder) return makeGrade(true, 1, "Correct. " + path, q);
  const std::size_t common = longestCommonSubsequence(ids, question.keyOrder);
  // Extra structures listed beyond the key lower the score as missing ones do.
  const double score = double(common) / double(std::max(ids.size(), question.keyOrder.size()));
  return makeGrade(false, score,
                   std::string(common > 0 ? "Partly right: " : "Not quite: ") + std::to_string(common) + " of " + std::to_string(question.keyOrder.size()) +
                       " structures in the right order. " + path,
                   q);
}

}  // namespace at::quiz
