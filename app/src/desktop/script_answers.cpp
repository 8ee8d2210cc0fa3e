// Helpers shared by the UI script's actions: answers to questions, errors, timeouts.
#include "script_answers.h"

#include "quiz/answer_json.h"

namespace at::app {

using json = nlohmann::json;

// A script's answer to the question asked: a choice (index, or a choice's id or name), a typed
// name, a list of structures (order), or a `play --answers` object.
Result<quiz::Answer> scriptAnswer(quiz::QuestionKind kind, const std::vector<std::string>& choiceIds,
                                  const std::vector<std::string>& choiceNames, const json& value) {
  if (value.is_object()) return quiz::answerFromJson(value.dump());
  quiz::Answer answer;
  switch (kind) {
    case quiz::QuestionKind::Locate:
      return fail("a locate question is answered by a click in the view (click, click_structure, slice_click)");
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation:
      if (value.is_number_integer()) {
        answer.choice = value.get<int>();
      } else if (value.is_string()) {  // the choice labelled so (its id or display name)
        const std::string wanted = value.get<std::string>();
        for (std::size_t i = 0; i < choiceIds.size(); ++i)
          if (choiceIds[i] == wanted || (i < choiceNames.size() && choiceNames[i] == wanted)) answer.choice = int(i);
        if (!answer.choice) return fail("'" + wanted + "' is not one of the choices");
      } else {
        return fail("answer a choice question with a number or a choice's id or name");
      }
      break;
    case quiz::QuestionKind::Name:
      if (!value.is_string()) return fail("answer a name question with a string");
      answer.text = value.get<std::string>();
      break;
    case quiz::QuestionKind::Order:
      if (!value.is_array()) return fail("answer an order question with a list of structures");
      answer.order = value.get<std::vector<std::string>>();
      break;
  }
  return answer;
}

tl::unexpected<Error> actionError(const json& action, const Error& e) {
  return tl::unexpected(withContext("ui script: action " + action.dump(), e));
}

tl::unexpected<Error> timedOut(const std::string& what) { return fail(ErrorKind::Unavailable, "ui script: " + what); }

}  // namespace at::app
