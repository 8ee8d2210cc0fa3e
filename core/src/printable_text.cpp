#include "core/printable_text.h"

#include <cstdint>
#include <cstdio>

namespace at {

namespace {

// Length of the valid UTF-8 sequence starting at text[i] and its code point; 0 if invalid.
std::size_t decodeUtf8(std::string_view text, std::size_t i, std::uint32_t& codePoint) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b0 = byte(i);
  std::size_t length = 0;
  std::uint32_t min = 0;
  if (b0 < 0x80) {
    codePoint = b0;
    return 1;
  } else if ((b0 & 0xE0) == 0xC0) {
    length = 2, min = 0x80, codePoint = b0 & 0x1F;
  } else if ((b0 & 0xF0) == 0xE0) {
    length = 3, min = 0x800, codePoint = b0 & 0x0F;
  } else if ((b0 & 0xF8) == 0xF0) {
    length = 4, min = 0x10000, codePoint = b0 & 0x07;
  } else {
    return 0;
  }
  if (i + length > text.size()) return 0;
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return 0;
    codePoint = (codePoint << 6) | (byte(i + k) & 0x3F);
  }
  if (codePoint < min || codePoint > 0x10FFFF || (codePoint >= 0xD800 && codePoint <= 0xDFFF)) return 0;
  return length;
}

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
    std::uint32_t c = 0;
    const std::size_t length = decodeUtf8(text, i, c);
    char escape[16];
    if (length == 0) {
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
  std::string out = printableLines(text);
  for (std::size_t at = out.find("##"); at != std::string::npos; at = out.find("##", at + 2)) out.insert(at + 1, " ");
  return out;
}

}  // namespace at
