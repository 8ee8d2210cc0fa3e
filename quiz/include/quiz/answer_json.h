// Answers as one-line JSON, the format of `play --answers` lines and of stored responses:
//   {"choice": 2}   {"text": "cochlea"}   {"pick": "stapes", "distance_mm": 0.3}   {"order": ["a","b"]}
// ("pick" may be "" or null for a click on nothing; "distance_mm" is optional; a pick on a picture
// also keeps "pixel": [x, y] and, on a fixed view, "view": its id).
#pragma once

#include <string>

#include "quiz/question.h"
#include "core/error.h"

namespace at::quiz {

std::string answerToJson(const Answer& answer);
// Errors name the problem: not JSON, not an object, unknown field, wrong type, no answer field,
// more than one answer field.
Result<Answer> answerFromJson(const std::string& line);

}  // namespace at::quiz
