#include "core/json_document.h"

#include <algorithm>
#include <optional>
#include <vector>

#include "core/printable_text.h"
#include "core/regular_file.h"

namespace at {

namespace {

using nlohmann::json;

// Builds the document through nlohmann's SAX interface (as json::parse does) while keeping the
// path of the value being read, so that a parse error can name its field, and refusing documents
// nested deeper than kMaxJsonDepth.
class DocumentBuilder {
 public:
  json root;
  std::string problem;    // set on failure
  std::optional<std::size_t> errorPosition;  // unknown for the builder's own refusals
  std::string errorField;

  bool null() { return value(nullptr); }
  bool boolean(bool v) { return value(v); }
  bool number_integer(json::number_integer_t v) { return value(v); }
  bool number_unsigned(json::number_unsigned_t v) { return value(v); }
  bool number_float(json::number_float_t v, const json::string_t&) { return value(v); }
  bool string(json::string_t& v) { return value(std::move(v)); }
  bool binary(json::binary_t& v) { return value(json::binary_t(std::move(v))); }
  bool start_object(std::size_t) { return open(json::value_t::object); }
  bool start_array(std::size_t) { return open(json::value_t::array); }
  bool end_object() { return close(); }
  bool end_array() { return close(); }
  bool key(json::string_t& k) {
    frames_.back().key = k;
    member_ = &(*frames_.back().container)[k];
    return true;
  }

  bool parse_error(std::size_t position, const std::string&, const nlohmann::detail::exception& e) {
    if (!problem.empty()) return false;  // our own refusal came first
    errorPosition = position;
    errorField = currentField(true);
    std::string what = e.what();
    // "[json.exception.parse_error.101] parse error at line 1, column 5: syntax error …" → "syntax error …"
    if (const std::size_t bracket = what.find("] "); what.rfind("[json.exception.", 0) == 0 && bracket != std::string::npos)
      what.erase(0, bracket + 2);
    if (what.rfind("parse error", 0) == 0)
      if (const std::size_t colon = what.find(": "); colon != std::string::npos) what.erase(0, colon + 2);
    if (e.id == 406) {
      // "number overflow parsing '1e309'"
      const std::size_t quote = what.find('\'');
      const std::string token = quote == std::string::npos ? what : what.substr(quote + 1, what.size() - quote - 2);
      problem = "number " + printableText(token, 40) + " is out of range (beyond ±1.8e308)";
    } else {
      problem = "not valid JSON: " + printableText(what, 200);
    }
    return false;
  }

 private:
  struct Frame {
    json* container;
    std::string key;  // objects: the member being read
  };

  template <class Value>
  bool value(Value&& v) {
    if (frames_.empty()) {
      root = json(std::forward<Value>(v));
      last_ = &root;
    } else if (frames_.back().container->is_array()) {
      frames_.back().container->emplace_back(std::forward<Value>(v));
      last_ = &frames_.back().container->back();
    } else {
      *member_ = json(std::forward<Value>(v));
      last_ = member_;
    }
    return true;
  }

  bool open(json::value_t type) {
    if (frames_.size() >= kMaxJsonDepth) {
      problem = "arrays and objects nested deeper than " + std::to_string(kMaxJsonDepth) + " levels";
      errorField = currentField(true);
      return false;
    }
    value(type);
    frames_.push_back({last_, {}});
    return true;
  }

  bool close() {
    frames_.pop_back();
    return true;
  }

  // "lessons[0].steps[2].question" — the value being read when `inner` (an array's next element).
  std::string currentField(bool inner) const {
    std::string path;
    for (std::size_t f = 0; f < frames_.size(); ++f) {
      const Frame& frame = frames_[f];
      const bool innermost = f + 1 == frames_.size();
      if (frame.container->is_array()) {
        const std::size_t size = frame.container->size();
        const std::size_t index = innermost && inner ? size : (size ? size - 1 : 0);
        path += '[';
        path += std::to_string(index);
        path += ']';
      } else if (!frame.key.empty() || frame.container->size()) {
        if (!path.empty()) path += '.';
        path += printableText(frame.key, 60);
      }
    }
    return path;
  }

  std::vector<Frame> frames_;
  json* member_ = nullptr;
  json* last_ = nullptr;
};

// "line 3, column 14" of a byte offset (both counted from 1).
std::string lineAndColumn(std::string_view text, std::size_t position) {
  position = std::min(position, text.size());
  const std::size_t line = 1 + std::size_t(std::count(text.begin(), text.begin() + std::ptrdiff_t(position), '\n'));
  const std::size_t lineStart = text.rfind('\n', position ? position - 1 : 0);
  const std::size_t column = lineStart == std::string_view::npos || position == 0 ? position + 1 : position - lineStart;
  return "line " + std::to_string(line) + ", column " + std::to_string(column);
}

}  // namespace

Result<json> parseJsonDocument(std::string_view text, const std::string& source) {
  DocumentBuilder builder;
  bool ok = false;
  try {
    ok = json::sax_parse(text.begin(), text.end(), &builder, json::input_format_t::json, true, false);
  } catch (const std::bad_alloc&) {
    throw;
  } catch (const std::exception& e) {
    // sax_parse reports through parse_error; anything else is unexpected but must not escape.
    return fail(source + ": cannot read the JSON (" + printableText(e.what(), 200) + ")");
  }
  if (!ok) {
    if (builder.problem.empty()) builder.problem = "not valid JSON";
    const std::string field = builder.errorField.empty() ? "" : ", field '" + builder.errorField + "'";
    const std::string where = builder.errorPosition ? ": " + lineAndColumn(text, *builder.errorPosition) : "";
    return fail(source + where + field + ": " + builder.problem);
  }
  return std::move(builder.root);
}

Result<json> readJsonFile(const std::string& path, const std::string& source, std::size_t maxBytes) {
  auto text = readRegularFile(path, source, maxBytes);
  if (!text) return tl::unexpected(text.error());
  return parseJsonDocument(*text, source);
}

}  // namespace at
