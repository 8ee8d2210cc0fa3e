#include "quiz/name_matching.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <sstream>

#include "core/utf8.h"

namespace at::quiz {
namespace {

// ASCII folding of U+00C0..U+00FF. Digits stand for two-letter folds: 3 = ae, 4 = th, 5 = ss;
// a space for the multiplication and division signs.
constexpr const char kLatin1[] = "aaaaaa3ceeeeiiiidnooooo ouuuuy45aaaaaa3ceeeeiiiidnooooo ouuuuy4y";
// ASCII folding of U+0100..U+017F. 1 = ij, 2 = oe.
constexpr const char kLatinExtA[] =
    "aaaaaaccccccccddddeeeeeeeeeegggggggghhhhiiiiiiiiii11jjkkkllllllllllnnnnnnnnnoooooo22rrrrrrssssssss"
    "ttttttuuuuuuuuuuuuwwyyyzzzzzzs";

void appendFold(std::string& out, char folded) {
  switch (folded) {
    case '1': out += "ij"; break;
    case '2': out += "oe"; break;
    case '3': out += "ae"; break;
    case '4': out += "th"; break;
    case '5': out += "ss"; break;
    default: out += folded;
  }
}

// Case- and accent-folded text with every non-alphanumeric character as a space.
std::string foldCharacters(const std::string& text) {
  std::string out;
  std::size_t i = 0;
  while (i < text.size()) {
    const std::size_t start = i;
    const Utf8Char ch = decodeUtf8At(text, i);
    const std::uint32_t cp = ch.codePoint;
    i += ch.length;
    if (cp < 0x80) {
      const char c = static_cast<char>(cp);
      if (c >= 'A' && c <= 'Z') out += static_cast<char>(c - 'A' + 'a');
      else if ((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9')) out += c;
      else out += ' ';
    } else if (cp >= 0xC0 && cp <= 0xFF) {
      appendFold(out, kLatin1[cp - 0xC0]);
    } else if (cp >= 0x100 && cp <= 0x17F) {
      appendFold(out, kLatinExtA[cp - 0x100]);
    } else if (cp >= 0x300 && cp <= 0x36F) {
      // combining diacritical mark: dropped, so decomposed "e" + U+0301 folds like "é"
    } else if (cp < 0xC0 || (cp >= 0x2000 && cp <= 0x206F) || cp == 0xFFFD) {
      out += ' ';  // Latin-1 punctuation, no-break space, general punctuation (’ – …), bad bytes
    } else {
      out.append(text, start, i - start);  // other scripts kept as they are
    }
  }
  return out;
}

}  // namespace

std::string normalizeName(const std::string& text) {
  std::istringstream words(foldCharacters(text));
  std::vector<std::string> body;
  std::vector<std::string> sides;
  std::string word;
  while (words >> word) {
    if (word == "the" || word == "a" || word == "an") continue;
    if (word == "left" || word == "l") sides.push_back("left");
    else if (word == "right" || word == "r") sides.push_back("right");
    else body.push_back(word);
  }
  std::string out;
  for (const auto* list : {&body, &sides}) {
    for (const std::string& w : *list) {
      if (!out.empty()) out += ' ';
      out += w;
    }
  }
  return out;
}

int damerauLevenshtein(const std::string& a, const std::string& b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<int>> d(n + 1, std::vector<int>(m + 1, 0));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = static_cast<int>(i);
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = static_cast<int>(j);
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const int cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[n][m];
}

int typoAllowance(std::size_t normalizedLength) {
  if (normalizedLength <= 4) return 0;
  if (normalizedLength <= 8) return 1;
  if (normalizedLength <= 16) return 2;
  return 3;
}

NameMatch matchName(const std::string& typed, const std::string& targetId,
                    const std::vector<std::string>& targetNames, const NameCatalog& catalog) {
  NameMatch match;
  const std::string text = normalizeName(typed);
  if (text.empty()) return match;

  std::size_t matchedLength = 0;
  for (const std::string& name : targetNames) {
    const std::string normal = normalizeName(name);
    if (normal.empty()) continue;
    const int distance = damerauLevenshtein(text, normal);
    if (match.distance < 0 || distance < match.distance) {
      match.distance = distance;
      match.matchedName = name;
      matchedLength = normal.size();
    }
  }
  if (match.distance < 0) return match;
  if (match.distance == 0) {
    match.accepted = true;
    return match;
  }
  if (match.distance > typoAllowance(matchedLength)) return match;

  // A typo is forgiven only when no other structure's spelling is as close.
  int closest = -1;
  for (const NameEntry& entry : catalog) {
    if (entry.structureId == targetId) continue;
    for (const std::string& name : entry.names) {
      const std::string normal = normalizeName(name);
      if (normal.empty()) continue;
      const int distance = damerauLevenshtein(text, normal);
      if (distance <= match.distance && (closest < 0 || distance < closest)) {
        closest = distance;
        match.closerStructure = entry.structureId;
        match.closerName = name;
      }
    }
  }
  match.accepted = closest < 0;
  return match;
}

namespace {

// Proper names that begin anatomical terms without a possessive: proper adjectives and eponyms
// used attributively (compared case-sensitively, as written in a name).
constexpr const char* kEponymousWords[] = {
    "Achilles", "Alcock",    "Arnold",   "Auerbach", "Bartholin", "Bowman",   "Broca",     "Brunner",
    "Calot",    "Corti",     "Cowper",   "Dorello",  "Eustachian", "Fallopian", "Glisson",  "Golgi",
    "Haversian", "Henle",    "Heschl",   "His",      "Hunter",    "Jacobson", "Kupffer",   "Langerhans",
    "Leydig",   "Luschka",   "Magendie", "Meckel",   "Meissner",  "Monro",    "Morison",   "Oddi",
    "Peyer",    "Purkinje",  "Reissner", "Rolandic", "Rosenthal", "Scarpa",   "Schlemm",   "Schwann",
    "Sertoli",  "Stensen",   "Sylvian",  "Treitz",   "Vater",     "Volkmann", "Wernicke",  "Wharton",
    "Willis",   "Wormian"};

bool isAsciiUpper(char c) { return c >= 'A' && c <= 'Z'; }

}  // namespace

std::string nameInSentence(const std::string& displayName) {
  if (displayName.empty() || !isAsciiUpper(displayName[0])) return displayName;
  const std::size_t end = std::min(displayName.find_first_of(" -/,("), displayName.size());
  const std::string first = displayName.substr(0, end);
  for (std::size_t i = 1; i < first.size(); ++i)
    if (isAsciiUpper(first[i]) || (first[i] >= '0' && first[i] <= '9')) return displayName;  // C1, IAC, CNVII
  for (const char* possessive : {"'s", "\xe2\x80\x99s", "s'", "s\xe2\x80\x99"})
    if (first.size() > std::strlen(possessive) && first.ends_with(possessive)) return displayName;
  for (const char* eponym : kEponymousWords)
    if (first == eponym) return displayName;
  std::string out = displayName;
  out[0] = char(out[0] - 'A' + 'a');
  return out;
}

}  // namespace at::quiz
