// Helpers shared by the UI script's actions (script_actions_*.cpp).
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "quiz/question.h"

namespace at::app {

// A script's answer to a question of `kind`: a choice (its index, or a choice's id or name), a
// typed name, a list of structures (order), or a `play --answers` object. Locate questions are
// answered by clicks, never here.
Result<quiz::Answer> scriptAnswer(quiz::QuestionKind kind, const std::vector<std::string>& choiceIds,
                                  const std::vector<std::string>& choiceNames, const nlohmann::json& value);

// The action's error, prefixed as the script's log shows it.
tl::unexpected<Error> actionError(const nlohmann::json& action, const Error& e);

// A timeout: something the script waited for never came (the script ends with status 1, not 2).
tl::unexpected<Error> timedOut(const std::string& what);

}  // namespace at::app
