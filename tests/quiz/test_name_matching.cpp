#include <doctest/doctest.h>

#include "quiz/name_matching.h"

using namespace at::quiz;

TEST_CASE("NormalizeName_FoldsCaseAccentsPunctuationAndMovesSidesLast") {
  CHECK(normalizeName("  Cochlea ") == "cochlea");
  CHECK(normalizeName("Nervus faciális") == "nervus facialis");
  CHECK(normalizeName("CÔTÉ Œuvre Straße") == "cote oeuvre strasse");
  CHECK(normalizeName("e\xCC\x81toile") == "etoile");  // decomposed é (e + U+0301)
  CHECK(normalizeName("semi-circular,canal") == "semi circular canal");
  CHECK(normalizeName("Left kidney") == "kidney left");
  CHECK(normalizeName("kidney (R)") == "kidney right");
  CHECK(normalizeName("The cochlea") == "cochlea");
  CHECK(normalizeName("it\xE2\x80\x99s") == "it s");  // curly apostrophe is punctuation
  CHECK(normalizeName("\xFF\xFE") == "");              // invalid UTF-8 does not crash
}

TEST_CASE("DamerauLevenshtein_CountsTranspositionsAsOneEdit") {
  CHECK(damerauLevenshtein("", "") == 0);
  CHECK(damerauLevenshtein("abc", "") == 3);
  CHECK(damerauLevenshtein("incus", "incsu") == 1);
  CHECK(damerauLevenshtein("stapes", "stapez") == 1);
  CHECK(damerauLevenshtein("malleus", "maleus") == 1);
  CHECK(damerauLevenshtein("kitten", "sitting") == 3);
  CHECK(damerauLevenshtein("ca", "abc") == 3);  // optimal string alignment, not full Damerau
}

TEST_CASE("TypoAllowance_GrowsWithLength") {
  CHECK(typoAllowance(4) == 0);
  CHECK(typoAllowance(5) == 1);
  CHECK(typoAllowance(8) == 1);
  CHECK(typoAllowance(9) == 2);
  CHECK(typoAllowance(17) == 3);
}
