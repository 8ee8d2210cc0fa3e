#include "core/printable_text.h"

#include <cstdint>
#include <cstdio>

#include "core/utf8.h"

namespace at {

namespace {

// Code points that move the cursor, start escape sequences or reorder text on display.
bool isControl(std::uint32_t c) {
  return c < 0x20 || (c >= 0x7F && c <= 0x9F) || c == 0x2028 || c == 0x2029 || (c >= 0x200E && c <= 0x200F) ||
         (c >= 0x202A && c <= 0x202E) || (c >= 0x2066 && c <= 0x2069) || c == 0xFEFF;
}

}  // namespace

namespace {

std::string escaped(std::string_view text, std::size_t maxChars, bool keepLines) {
  std::string out;
  out.reserve(text.size() < maxChars ? text.size() : maxChars);
  std::size_t chars = 0;
  for (std::size_t i = 0; i < text.size();) {
    if (chars == maxChars) {
      out += "…";
      break;
    }
    const Utf8Char decoded = decodeUtf8At(text, i);
    const std::uint32_t c = decoded.codePoint;
    const std::size_t length = decoded.length;
    char escape[16];
    if (!decoded.valid) {
      std::snprintf(escape, sizeof escape, "\\x%02x", unsigned(static_cast<unsigned char>(text[i])));
      out += escape;
      i += 1;
    } else if (keepLines && (c == '\n' || c == '\t')) {
      out += char(c);
      i += length;
    } else if (isControl(c)) {
      if (c == '\n')
        out += "\\n";
      else if (c == '\r')
        out += "\\r";
      else if (c == '\t')
        out += "\\t";
      else if (c < 0x100)
        std::snprintf(escape, sizeof escape, "\\x%02x", unsigned(c)), out += escape;
      else
        std::snprintf(escape, sizeof escape, "\\u%04x", unsigned(c)), out += escape;
      i += length;
    } else {
      out.append(text.substr(i, length));
      i += length;
    }
    ++chars;
  }
  return out;
}

}  // namespace

std::string printableText(std::string_view text, std::size_t maxChars) { return escaped(text, maxChars, false); }

std::string printableLines(std::string_view text) { return escaped(text, std::string_view::npos, true); }

std::string printableUiText(std::string_view text) {
  const std::string lines = printableLines(text);
  std::string out;
  out.reserve(lines.size());
  for (std::size_t i = 0; i < lines.size(); ++i) {
    out += lines[i];
    if (lines[i] == '#' && i + 1 < lines.size() && lines[i + 1] == '#') out += ' ';  // "##" → "# #"
  }
  return out;
}

}  // namespace at
