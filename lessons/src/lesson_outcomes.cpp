// The end-of-lesson review: each question with the student's answer and the key, in words.
#include "lessons/lesson_engine.h"

namespace at::lessons {
namespace {

std::string joined(const std::vector<std::string>& ids, const quiz::GradingContext& context) {
  std::string out;
  for (const std::string& id : ids) out += (out.empty() ? "" : " → ") + context.displayName(id);
  return out;
}

}  // namespace

QuestionScene showMeScene(const Step& questionStep) { return showMeScene(sceneFor(questionStep), questionStep.question.target); }

QuestionScene showMeScene(QuestionScene scene, const std::string& target) {
  if (!target.empty() && scene.structure != target) {
    scene.structure = target;
    scene.presetId = target + "_wdt";
  }
  return scene;
}

std::string rightAnswerText(const quiz::ResolvedQuestion& question, const quiz::GradingContext& context) {
  const quiz::Question& q = question.question;
  switch (q.kind) {
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation:
      if (question.keyChoice >= 0 && question.keyChoice < int(question.choices.size()))
        return context.displayName(question.choices[std::size_t(question.keyChoice)]);
      break;
    case quiz::QuestionKind::Order:
      return joined(question.keyOrder, context);
    case quiz::QuestionKind::Name:
      return q.askSide ? context.displayName(q.target) : context.baseName(q.target);
    case quiz::QuestionKind::Locate:
      break;
  }
  return context.displayName(q.target);
}

std::string answerText(const quiz::ResolvedQuestion& question, const quiz::Answer& answer,
                       const quiz::GradingContext& context) {
  if (answer.text) return "\"" + *answer.text + "\"";
  if (answer.choice) {
    if (*answer.choice >= 0 && *answer.choice < int(question.choices.size()))
      return context.displayName(question.choices[std::size_t(*answer.choice)]);
    return "choice " + std::to_string(*answer.choice);
  }
  if (answer.pick) return answer.pick->structure.empty() ? "a click on no structure" : "a click on the " + context.nameInSentence(answer.pick->structure);
  if (answer.order) return joined(*answer.order, context);
  return "";
}

std::vector<int> LessonEngine::upcomingSteps(int count) const {
  std::vector<int> out;
  for (std::size_t p = cursor_ + 1; p < shown_.size() && int(out.size()) < count; ++p) out.push_back(shown_[p]);
  return out;
}

std::vector<QuestionOutcome> LessonEngine::outcomes() const {
  std::vector<QuestionOutcome> out;
  if (!attempt_) return out;
  const quiz::GradingContext context = gradingContext(structures_, course_);
  for (std::size_t p = 0; p < shown_.size(); ++p) {
    const std::size_t index = std::size_t(shown_[p]);
    if (!resolved_[index]) continue;
    if (p > cursor_ && !grades_[index]) continue;  // not reached yet
    const quiz::ResolvedQuestion& q = *resolved_[index];
    QuestionOutcome o;
    o.position = int(p) + 1;
    o.questionId = q.question.id;
    o.kind = q.question.kind;
    o.prompt = q.question.prompt;
    o.target = q.question.target;
    o.rightAnswer = rightAnswerText(q, context);
    if (answers_[index]) o.yourAnswer = answerText(q, *answers_[index], context);
    o.grade = grades_[index];
    o.scene = showMeScene(lesson_.steps[index]);
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace at::lessons
