// Outside text made safe for one-line messages and terminals.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "core/printable_text.h"
#include "test_support.h"

using namespace at;

TEST_CASE("PrintableText_ControlCharactersAndEscapeSequences_BecomeVisibleEscapes") {
  CHECK(printableText("liver\n\x1b[31mred\x1b[0m\r\tend") == "liver\\n\\x1b[31mred\\x1b[0m\\r\\tend");
  CHECK(printableText(std::string("nul\0byte", 8)) == "nul\\x00byte");
  CHECK(printableText("del\x7f") == "del\\x7f");
  // C1 controls (U+009B is a one-byte CSI for some terminals), line separators, bidi overrides.
  CHECK(printableText("csi\xc2\x9b" "2J") == "csi\\x9b2J");
  CHECK(printableText("a\xe2\x80\xa8" "b") == "a\\u2028b");
  CHECK(printableText("evil\xe2\x80\xae" "txt.exe") == "evil\\u202etxt.exe");
}

TEST_CASE("PrintableText_ValidUtf8IsKept_InvalidBytesAreEscaped") {
  CHECK(printableText("Ösophagus — 耳蜗") == "Ösophagus — 耳蜗");
  CHECK(printableText("bad\xff\xfe") == "bad\\xff\\xfe");
  CHECK(printableText("overlong\xc0\xaf") == "overlong\\xc0\\xaf");
  CHECK(printableText("surrogate\xed\xa0\x80") == "surrogate\\xed\\xa0\\x80");
  CHECK(printableText("cut\xe8\x80") == "cut\\xe8\\x80");
}

TEST_CASE("PrintableText_LongTextIsCutAfterMaxCharacters") {
  CHECK(printableText("abcdef", 3) == "abc…");
  CHECK(printableText("äöü", 2) == "äö…");
  CHECK(printableText("abc", 3) == "abc");
}

TEST_CASE("PrintableError_KeepsTheKind_AndMakesTheMessageOneLine") {
  const Error e = printableError(Error{ErrorKind::NotFound, "x.json: key \"a\nb\" unknown"});
  CHECK((e.kind == ErrorKind::NotFound));
  CHECK(e.message == "x.json: key \"a\\nb\" unknown");
}

namespace {

// True if `s` is valid UTF-8 holding no control a terminal acts on: no C0 but \n and \t, no DEL,
// no C1, no line/paragraph separator, no bidirectional control.
bool safeForTerminal(const std::string& s) {
  for (std::size_t i = 0; i < s.size();) {
    const auto b = static_cast<unsigned char>(s[i]);
    std::uint32_t c = 0;
    std::size_t n = 0;
    if (b < 0x80) c = b, n = 1;
    else if ((b & 0xE0) == 0xC0) c = b & 0x1F, n = 2;
    else if ((b & 0xF0) == 0xE0) c = b & 0x0F, n = 3;
    else if ((b & 0xF8) == 0xF0) c = b & 0x07, n = 4;
    else return false;
    if (i + n > s.size()) return false;
    for (std::size_t k = 1; k < n; ++k) {
      if ((static_cast<unsigned char>(s[i + k]) & 0xC0) != 0x80) return false;
      c = (c << 6) | (static_cast<unsigned char>(s[i + k]) & 0x3F);
    }
    if ((c < 0x20 && c != '\n' && c != '\t') || (c >= 0x7F && c <= 0x9F)) return false;
    if (c == 0x2028 || c == 0x2029 || c == 0x200E || c == 0x200F || (c >= 0x202A && c <= 0x202E) ||
        (c >= 0x2066 && c <= 0x2069) || c == 0xFEFF)
      return false;
    i += n;
  }
  return true;
}

}  // namespace

TEST_CASE("PrintableLines_RandomControlBytes_NeverReachTheOutputRaw") {
  const std::uint64_t seed = at::test::freshSeed("PrintableLines_RandomControlBytes");
  INFO("seed " << seed);
  std::mt19937 random{unsigned(seed)};
  // Pieces a hostile title would use, mixed with plain and accented text and random bytes.
  const std::vector<std::string> pieces = {"\x1b[2J", "\x1b]0;owned\x07", "\xc2\x9b" "31m", "\xe2\x80\xae", "\xe2\x81\xa6",
                                           "\r", "\b", "\x7f", "\n", "\t", "liver", "Ösophagus", "耳蜗", "\xff", "\xc0\xaf",
                                           "\xe2\x80\xa8", "\xef\xbb\xbf", "\xed\xa0\x80"};
  for (int round = 0; round < 2000; ++round) {
    std::string text;
    const int parts = int(random() % 12);
    for (int p = 0; p < parts; ++p) {
      if (random() % 3 == 0) text += char(random() % 256);
      else text += pieces[random() % pieces.size()];
    }
    const std::string shown = printableLines(text);
    REQUIRE_MESSAGE(safeForTerminal(shown), "round " << round);
    CHECK(shown.find('\x1b') == std::string::npos);
    // Line breaks and tabs are kept; printable text comes through unchanged.
    CHECK(std::count(shown.begin(), shown.end(), '\n') == std::count(text.begin(), text.end(), '\n'));
    CHECK(safeForTerminal(printableText(text, 10000)));
  }
  CHECK(printableLines("Liver\n\tsegment VIII — 耳蜗") == "Liver\n\tsegment VIII — 耳蜗");
  CHECK(printableLines("\x1b[2Jall answers correct") == "\\x1b[2Jall answers correct");
}

TEST_CASE("PrintableUiText_HiddenIdMarkerAndControls_ShownNotInterpreted") {
  CHECK(printableUiText("Ear##secret") == "Ear# #secret");
  CHECK(printableUiText("###") == "# # #");
  CHECK(printableUiText("a\x1b[2Jb\nc") == "a\\x1b[2Jb\nc");
  CHECK(printableUiText("耳蜗 — 100%") == "耳蜗 — 100%");
}
