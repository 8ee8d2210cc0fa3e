// Outside text made safe for one-line messages and terminals.
#include <doctest/doctest.h>

#include "core/printable_text.h"

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
