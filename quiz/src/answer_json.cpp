#include "quiz/answer_json.h"

#include <cmath>

#include <nlohmann/json.hpp>

#include "core/json_document.h"
#include "core/printable_text.h"

namespace at::quiz {

std::string answerToJson(const Answer& answer) {
  nlohmann::json j = nlohmann::json::object();
  if (answer.choice) j["choice"] = *answer.choice;
  if (answer.text) j["text"] = *answer.text;
  if (answer.pick) {
    j["pick"] = answer.pick->structure;
    if (std::isfinite(answer.pick->distanceMm) && answer.pick->distanceMm >= 0) {
      j["distance_mm"] = answer.pick->distanceMm;
    }
    if (answer.pick->pixel) j["pixel"] = *answer.pick->pixel;
    if (!answer.pick->view.empty()) j["view"] = answer.pick->view;
  }
  if (answer.order) j["order"] = *answer.order;
  return j.dump();
}

namespace {

Result<Answer> readAnswer(const nlohmann::json& j) {
  if (!j.is_object()) return fail("an answer must be a JSON object such as {\"choice\": 1}");
  Answer answer;
  int fields = 0;
  for (const auto& [key, value] : j.items()) {
    if (key == "choice") {
      if (!value.is_number_integer()) return fail("choice: must be an integer index");
      answer.choice = value.get<int>();
      ++fields;
    } else if (key == "text") {
      if (!value.is_string()) return fail("text: must be a string");
      answer.text = value.get<std::string>();
      ++fields;
    } else if (key == "pick") {
      if (!value.is_string() && !value.is_null()) return fail("pick: must be a structure id or null");
      Pick pick;
      pick.structure = value.is_null() ? "" : value.get<std::string>();
      if (j.contains("distance_mm")) {
        const auto& d = j["distance_mm"];
        if (!d.is_number() || d.get<double>() < 0) return fail("distance_mm: must be a number >= 0");
        pick.distanceMm = d.get<double>();
      }
      if (j.contains("pixel")) {
        const auto& p = j["pixel"];
        if (!p.is_array() || p.size() != 2 || !p[0].is_number_integer() || !p[1].is_number_integer())
          return fail("pixel: must be [x, y] in whole pixels");
        pick.pixel = std::array<int, 2>{p[0].get<int>(), p[1].get<int>()};
      }
      if (j.contains("view")) {
        if (!j["view"].is_string() || !pick.pixel) return fail("view: must be the id of the view a pixel was picked on");
        pick.view = j["view"].get<std::string>();
      }
      answer.pick = pick;
      ++fields;
    } else if (key == "distance_mm" || key == "pixel" || key == "view") {
      if (!j.contains("pick")) return fail(key + ": only allowed with pick");
    } else if (key == "order") {
      if (!value.is_array()) return fail("order: must be an array of structure ids");
      std::vector<std::string> order;
      for (const auto& item : value) {
        if (!item.is_string()) return fail("order: every entry must be a string");
        order.push_back(item.get<std::string>());
      }
      answer.order = order;
      ++fields;
    } else {
      return fail("unknown field '" + printableText(key, 40) + "' (expected choice, text, pick with distance_mm, pixel and view, or order)");
    }
  }
  if (fields == 0) return fail("no answer: give one of choice, text, pick or order");
  if (fields > 1) return fail("more than one answer field: give exactly one of choice, text, pick or order");
  return answer;
}

}  // namespace

Result<Answer> answerFromJson(const std::string& line) {
  // The caller names the file and line ("answers.jsonl:3: column 5: not valid JSON: …"): of the
  // parser's position only the column within this line is kept.
  auto j = parseJsonDocument(line, "answer");
  if (!j) {
    Error e = j.error();
    constexpr std::string_view kPrefix = "answer: line 1, ";
    if (e.message.rfind(kPrefix, 0) == 0) e.message.erase(0, kPrefix.size());
    return tl::unexpected(e);
  }
  return withPrintableError(readAnswer(*j));
}

}  // namespace at::quiz
