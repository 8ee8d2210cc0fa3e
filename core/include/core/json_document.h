// Reading JSON from outside (presets, courses, questions, answers, study protocols, label names):
// one parser for every reader, so that every problem the parser meets — bad syntax, a number beyond
// the range of a double (1e309), nesting too deep — comes back as an Error naming the source, the
// line, the column and the field it was reading ("course.json: line 12, column 22, field
// 'lessons[0].steps[1].question.difficulty': number 1e309 is out of range"), exactly as the readers'
// own validation errors name their fields. Nothing here throws.
// Target at_core_json (at_core stays free of third-party headers).
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "core/error.h"

namespace at {

// Deepest nesting of arrays and objects accepted (the readers' documents use fewer than ten).
inline constexpr std::size_t kMaxJsonDepth = 256;

// Parses `text` (all of it: trailing garbage is an error). `source` starts every error message.
Result<nlohmann::json> parseJsonDocument(std::string_view text, const std::string& source);

// Reads a JSON file and parses it; `source` starts every error message (the path or the file's
// name). Refuses what is not a regular file (a FIFO would block, a device never end) and files over
// `maxBytes`.
Result<nlohmann::json> readJsonFile(const std::string& path, const std::string& source,
                                    std::size_t maxBytes = std::size_t(64) << 20);

}  // namespace at
