#include "quiz/grading.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "quiz/sided_names.h"

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

const NameEntry* GradingContext::entry(const std::string& structureId) const {
  for (const NameEntry& e : names)
    if (e.structureId == structureId) return &e;
  return nullptr;
}

std::string GradingContext::baseName(const std::string& structureId) const {
  const NameEntry* e = entry(structureId);
  if (e && !e->baseName.empty()) return e->baseName;
  return withoutSide(displayName(structureId));
}

Side GradingContext::side(const std::string& structureId) const {
  const NameEntry* e = entry(structureId);
  if (e && e->side != Side::None) return e->side;
  return sideOfName(displayName(structureId));
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
  NameEntry target;
  target.structureId = q.target;
  if (const NameEntry* e = context.entry(q.target)) target = *e;
  if (target.names.empty()) target.names.push_back(q.target);
  target.names.insert(target.names.end(), q.synonyms.begin(), q.synonyms.end());
  const Side targetSide = context.side(q.target);
  const bool sideAsked = q.askSide && targetSide != Side::None;
  const std::string base = context.baseName(q.target);
  const std::string baseInSentence = quiz::nameInSentence(base);
  // The name feedback shows: with the side only when the question asks for it.
  const auto shown = [&](const std::string& id) {
    return sideAsked ? context.nameInSentence(id) : quiz::nameInSentence(context.baseName(id));
  };
  const std::string sideWord = toString(targetSide);

  const SidedMatch match = matchSidedName(text, target, context.names);
  if (!match.nameAccepted) {
    if (!match.closerStructure.empty()) {
      return makeGrade(false, 0,
                       "Not quite: \"" + text + "\" reads as the " + shown(match.closerStructure) + "; this is the " +
                           shown(q.target) + ".",
                       q);
    }
    return makeGrade(false, 0, "Not quite: this is the " + shown(q.target) + ".", q);
  }
  const std::string spelling = match.distance > 0 ? " (mind the spelling: " + match.matchedName + ")" : "";
  if (!sideAsked) {
    std::string feedback = "Correct: " + base + spelling + ".";
    if (targetSide != Side::None && match.typedSide != Side::None && match.typedSide != targetSide) {
      feedback += " (This one is the patient's " + sideWord + ".)";
    }
    return makeGrade(true, 1, feedback, q);
  }
  if (match.typedSide == targetSide && !match.sideConflicting) {
    return makeGrade(true, 1, "Correct: " + context.displayName(q.target) + spelling + ".", q);
  }
  const std::string hint = " Left and right are the patient's, not the screen's.";
  if (match.typedSide == Side::None) {
    return makeGrade(false, 0.5,
                     "Which side? You named the " + baseInSentence + spelling +
                         ", but the question asks for the side: this is the patient's " + sideWord + " one." + hint,
                     q);
  }
  return makeGrade(false, 0.25,
                   "Right structure, wrong side: this is the patient's " + sideWord + " " + baseInSentence + "." + hint,
                   q);
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
