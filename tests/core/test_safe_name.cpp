// The one rule for outside names (core/safe_name.h) and the one confined-path function.
#include <doctest/doctest.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <cctype>
#include <random>
#include <string>

#include "core/safe_name.h"
#include "test_support.h"

using namespace at;
namespace fs = std::filesystem;

namespace {

// The rule written out independently of the implementation.
bool byTheRule(const std::string& s) {
  if (s.empty() || s.size() > kMaxSafeNameBytes) return false;
  for (unsigned char c : s)
    if (!std::isalnum(c) || c >= 0x80)
      if (c != '_' && c != '-' && c != '.') return false;
  const char first = s.front();
  return first != '.' && first != '-' && s.back() != '.';
}

fs::path freshFolder(const std::string& tag) {
  fs::path dir = fs::temp_directory_path() / ("at-safe-name-" + tag + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

}  // namespace

TEST_CASE("SafeName_HostileNames_AreRefusedWithOneLineNamingTheField") {
  const char* hostile[] = {"",          "/",         "/home/user/x", "../../../x", ".",  "..",  "a/b",  "a\\b",
                           "-rf",       "--name",    ".hidden",      "name.",      "a b", "a:b", "a\nb", "a\x1b[2Jb",
                           "sk\xd1\x83ll" /* Cyrillic u */, "cafe\xcc\x81" /* combining accent */, "\xef\xbd\x81" /* fullwidth a */};
  for (const char* name : hostile) {
    CAPTURE(name);
    CHECK_FALSE(isSafeName(name));
    auto st = checkSafeName("manifest.json: dataset.name", name);
    REQUIRE_FALSE(st);
    CHECK((st.error().kind == ErrorKind::Invalid));
    CHECK(st.error().message.rfind("manifest.json: dataset.name '", 0) == 0);
    CHECK(st.error().message.find('\n') == std::string::npos);
    CHECK(st.error().message.find('\x1b') == std::string::npos);
  }
  CHECK_FALSE(isSafeName(std::string(kMaxSafeNameBytes + 1, 'a')));
  for (const char* name : {"skull", "temporal_bone", "ear_quiz.lesson_1.show_1", "cochlea_wdt", "_x", "A-1", "volume.nrrd"})
    CHECK(isSafeName(name));
  CHECK(isSafeName(std::string(kMaxSafeNameBytes, 'a')));
}

TEST_CASE("SafeName_RandomStrings_AgreeWithTheWrittenRule") {
  const std::uint64_t seed = at::test::freshSeed("SafeName_RandomStrings");
  INFO("seed " << seed);
  std::mt19937 rng{unsigned(seed)};
  const std::string alphabet = std::string("aZ09_-./\\: \x01\x7f") + "\xc3\xa9";
  std::uniform_int_distribution<std::size_t> pick(0, alphabet.size() - 1), length(0, 8);
  int safe = 0;
  for (int i = 0; i < 20000; ++i) {
    std::string s;
    for (std::size_t n = length(rng); n > 0; --n) s += alphabet[pick(rng)];
    CAPTURE(s);
    CHECK(isSafeName(s) == byTheRule(s));
    safe += isSafeName(s);
  }
  CHECK(safe > 100);  // the draw reached both sides of the rule
}

TEST_CASE("ConfinedPath_StaysInsideTheFolder_EvenThroughSymbolicLinks") {
  const fs::path base = freshFolder("base"), outside = freshFolder("outside");
  auto inside = confinedPath(base, {"datasets", "skull"}, "dataset");
  REQUIRE(inside);
  CHECK(*inside == base / "datasets" / "skull");
  CHECK_FALSE(fs::exists(*inside));  // nothing is created

  for (std::string_view bad : {"..", "../x", "/etc", "a/b", ""}) {
    auto refused = confinedPath(base, {"datasets", bad}, "dataset");
    REQUIRE_FALSE(refused);
    CHECK(refused.error().message.rfind("dataset", 0) == 0);
  }
  // A link inside the data folder that points out of it is not followed out.
  fs::create_directories(base / "datasets");
  fs::create_directory_symlink(outside, base / "datasets" / "escape");
  auto through = confinedPath(base, {"datasets", "escape", "volume.nrrd"}, "dataset");
  REQUIRE_FALSE(through);
  CHECK(through.error().message.find("outside") != std::string::npos);
  CHECK_FALSE(isInside(base, base));
  CHECK(isInside(base, base / "a"));
  CHECK_FALSE(isInside(base / "a", base / "ab"));
  fs::remove_all(base);
  fs::remove_all(outside);
}
