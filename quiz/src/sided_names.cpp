#include "quiz/sided_names.h"

#include <cctype>
#include <set>
#include <sstream>

namespace at::quiz {
namespace {

std::string lowerAscii(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Side-free normalised spellings of an entry.
std::set<std::string> bodiesOf(const NameEntry& entry) {
  std::set<std::string> out;
  for (const std::string& name : entry.names) {
    const SidedName split = splitSide(name);
    if (!split.body.empty()) out.insert(split.body);
  }
  if (!entry.baseName.empty()) out.insert(splitSide(entry.baseName).body);
  return out;
}

}  // namespace

const char* toString(Side side) {
  switch (side) {
    case Side::Left: return "left";
    case Side::Right: return "right";
    case Side::None: break;
  }
  return "";
}

SidedName splitSide(const std::string& name) {
  std::istringstream words(normalizeName(name));
  SidedName out;
  bool left = false, right = false;
  std::string word;
  while (words >> word) {
    if (word == "left") left = true;
    else if (word == "right") right = true;
    else out.body += (out.body.empty() ? "" : " ") + word;
  }
  out.conflicting = left && right;
  out.side = out.conflicting ? Side::None : left ? Side::Left : right ? Side::Right : Side::None;
  return out;
}

std::string withoutSide(const std::string& name) {
  // Words are split at spaces and brackets; a side word is dropped with its brackets.
  std::string out;
  std::string word;
  const auto flush = [&] {
    const std::string bare = lowerAscii(word);
    const bool side = bare == "left" || bare == "right" || bare == "(left)" || bare == "(right)" ||
                      bare == "left," || bare == "right,";
    if (!word.empty() && !side) out += (out.empty() ? "" : " ") + word;
    word.clear();
  };
  for (char c : name) {
    if (c == ' ') flush();
    else word += c;
  }
  flush();
  while (!out.empty() && (out.back() == ',' || out.back() == '-' || out.back() == ' ')) out.pop_back();
  if (out.empty()) return name;
  if (!name.empty() && std::isupper(static_cast<unsigned char>(name[0])) &&
      std::islower(static_cast<unsigned char>(out[0]))) {
    out[0] = char(std::toupper(static_cast<unsigned char>(out[0])));
  }
  return out;
}

Side sideOfName(const std::string& displayName) { return splitSide(displayName).side; }

SidedMatch matchSidedName(const std::string& typed, const NameEntry& target, const NameCatalog& catalog) {
  SidedMatch match;
  const SidedName text = splitSide(typed);
  match.typedSide = text.side;
  match.sideConflicting = text.conflicting;
  if (text.body.empty()) return match;

  std::size_t matchedLength = 0;
  for (const std::string& name : target.names) {
    const std::string body = splitSide(name).body;
    if (body.empty()) continue;
    const int distance = damerauLevenshtein(text.body, body);
    if (match.distance < 0 || distance < match.distance) {
      match.distance = distance;
      match.matchedName = withoutSide(name);
      matchedLength = body.size();
    }
  }
  if (match.distance < 0) return match;
  if (match.distance == 0) {
    match.nameAccepted = true;
    return match;
  }
  if (match.distance > typoAllowance(matchedLength)) return match;

  // A typo is forgiven only when no other structure's spelling is as close; the target's own
  // spellings on the other side (its counterpart) do not compete.
  const std::set<std::string> targetBodies = bodiesOf(target);
  int closest = -1;
  for (const NameEntry& entry : catalog) {
    if (entry.structureId == target.structureId) continue;
    for (const std::string& name : entry.names) {
      const std::string body = splitSide(name).body;
      if (body.empty() || targetBodies.count(body)) continue;
      const int distance = damerauLevenshtein(text.body, body);
      if (distance <= match.distance && (closest < 0 || distance < closest)) {
        closest = distance;
        match.closerStructure = entry.structureId;
      }
    }
  }
  match.nameAccepted = closest < 0;
  return match;
}

}  // namespace at::quiz
