// UTF-8 text from outside, one character at a time: the one decoder that printable text, name
// matching and the built-in bitmap font share, so that each treats a bad byte the same way.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace at {

// One character of UTF-8 text: its code point and how many bytes it takes.
struct Utf8Char {
  std::uint32_t codePoint = 0;
  std::size_t length = 0;
  bool valid = false;
};

// The character that starts at text[i] (i < text.size()). A byte that does not start a valid
// sequence (a stray continuation byte, a sequence cut short, an overlong form, a surrogate, a code
// point beyond U+10FFFF) gives U+FFFD, length 1 and valid false, so a reader steps over bad bytes
// one at a time and always moves forward.
Utf8Char decodeUtf8At(std::string_view text, std::size_t i);

// The number of characters of `text`, each invalid byte counted as one.
std::size_t utf8Length(std::string_view text);

// The longest prefix of `text` of at most `maxChars` characters: never ends inside a sequence.
std::string_view utf8Prefix(std::string_view text, std::size_t maxChars);

}  // namespace at
