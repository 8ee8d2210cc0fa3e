// The one UTF-8 decoder of outside text (core/utf8.h).
#include <doctest/doctest.h>

#include <cstdint>
#include <random>
#include <string>

#include "core/utf8.h"

using namespace at;

namespace {

std::string encoded(std::uint32_t cp) {
  std::string out;
  if (cp < 0x80) {
    out += char(cp);
  } else if (cp < 0x800) {
    out += char(0xC0 | (cp >> 6)), out += char(0x80 | (cp & 0x3F));
  } else if (cp < 0x10000) {
    out += char(0xE0 | (cp >> 12)), out += char(0x80 | ((cp >> 6) & 0x3F)), out += char(0x80 | (cp & 0x3F));
  } else {
    out += char(0xF0 | (cp >> 18)), out += char(0x80 | ((cp >> 12) & 0x3F));
    out += char(0x80 | ((cp >> 6) & 0x3F)), out += char(0x80 | (cp & 0x3F));
  }
  return out;
}

}  // namespace

TEST_CASE("Utf8_EveryCodePointDecodesToItself") {
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::uint32_t> any(0, 0x10FFFF);
  for (int k = 0; k < 20000; ++k) {
    std::uint32_t cp = k < 256 ? std::uint32_t(k) : any(rng);
    if (cp >= 0xD800 && cp <= 0xDFFF) continue;
    const std::string text = encoded(cp) + "x";
    const Utf8Char ch = decodeUtf8At(text, 0);
    REQUIRE(ch.valid);
    CHECK(ch.codePoint == cp);
    CHECK(ch.length == text.size() - 1);
  }
  CHECK(utf8Length("µCT — 耳蜗 𝛼") == 10);
}

TEST_CASE("Utf8_BadBytesAreOneReplacementCharacterEach") {
  for (const std::string bad : {"\xff", "\x80", "\xc0\xaf", "\xe0\x80\xaf", "\xed\xa0\x80", "\xf4\x90\x80\x80", "\xe8\x80",
                                "\xc3"}) {
    const Utf8Char ch = decodeUtf8At(bad, 0);
    CHECK_FALSE(ch.valid);
    CHECK(ch.codePoint == 0xFFFD);
    CHECK(ch.length == 1);
  }
  CHECK(utf8Length("a\xe8\x80z") == 4);  // a, two bad bytes, z
}

TEST_CASE("Utf8_ARandomByteStringIsWalkedToItsEndAndPrefixesNeverCutASequence") {
  std::mt19937 rng(11);
  const std::string pieces[] = {"a", " ", "µ", "é", "—", "耳", "𝛼", "\xff", "\xe8\x80", "\x80"};
  for (int round = 0; round < 2000; ++round) {
    std::string text;
    const int n = int(rng() % 12);
    for (int k = 0; k < n; ++k) text += pieces[rng() % std::size(pieces)];
    std::size_t steps = 0, i = 0;
    while (i < text.size()) {
      const Utf8Char ch = decodeUtf8At(text, i);
      REQUIRE(ch.length >= 1);
      i += ch.length, ++steps;
    }
    CHECK(i == text.size());
    CHECK(steps == utf8Length(text));
    for (std::size_t chars = 0; chars <= steps + 1; ++chars) {
      const std::string_view prefix = utf8Prefix(text, chars);
      CHECK(utf8Length(prefix) == std::min(chars, steps));
      // What follows the prefix starts where a character starts.
      std::size_t j = 0;
      while (j < prefix.size()) j += decodeUtf8At(text, j).length;
      CHECK(j == prefix.size());
    }
  }
}
