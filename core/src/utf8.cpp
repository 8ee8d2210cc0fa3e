#include "core/utf8.h"

namespace at {

Utf8Char decodeUtf8At(std::string_view text, std::size_t i) {
  constexpr Utf8Char kInvalid{0xFFFD, 1, false};
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b0 = byte(i);
  if (b0 < 0x80) return {b0, 1, true};
  std::size_t length = 0;
  std::uint32_t min = 0, codePoint = 0;
  if ((b0 & 0xE0) == 0xC0) {
    length = 2, min = 0x80, codePoint = b0 & 0x1F;
  } else if ((b0 & 0xF0) == 0xE0) {
    length = 3, min = 0x800, codePoint = b0 & 0x0F;
  } else if ((b0 & 0xF8) == 0xF0) {
    length = 4, min = 0x10000, codePoint = b0 & 0x07;
  } else {
    return kInvalid;
  }
  if (i + length > text.size()) return kInvalid;
  for (std::size_t k = 1; k < length; ++k) {
    if ((byte(i + k) & 0xC0) != 0x80) return kInvalid;
    codePoint = (codePoint << 6) | (byte(i + k) & 0x3F);
  }
  if (codePoint < min || codePoint > 0x10FFFF || (codePoint >= 0xD800 && codePoint <= 0xDFFF)) return kInvalid;
  return {codePoint, length, true};
}

std::size_t utf8Length(std::string_view text) {
  std::size_t chars = 0;
  for (std::size_t i = 0; i < text.size(); i += decodeUtf8At(text, i).length) ++chars;
  return chars;
}

std::string_view utf8Prefix(std::string_view text, std::size_t maxChars) {
  std::size_t i = 0;
  for (std::size_t chars = 0; chars < maxChars && i < text.size(); ++chars) i += decodeUtf8At(text, i).length;
  return text.substr(0, i);
}

}  // namespace at
