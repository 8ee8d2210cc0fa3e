// core/: errors keep their kind through context, and the string helpers on their edge cases.
#include <doctest/doctest.h>

#include "core/error.h"
#include "core/strings.h"

using namespace at;

namespace {
Result<int> lookUp(bool present) {
  if (!present) return fail(ErrorKind::NotFound, "no structure 'stapes'");
  return 7;
}
Result<int> lookUpWithContext(bool present) {
  auto r = lookUp(present);
  if (!r) return tl::unexpected(withContext("lesson 'inner_ear'", r.error()));
  return r;
}
}  // namespace

TEST_CASE("Fail_WithoutKind_IsInvalid_AndWithKind_KeepsIt") {
  const Status plain = fail("bad --size");
  REQUIRE_FALSE(plain);
  CHECK((plain.error().kind == ErrorKind::Invalid));
  CHECK(plain.error().message == "bad --size");
  const Status conflict = fail(ErrorKind::Conflict, "name taken");
  CHECK((conflict.error().kind == ErrorKind::Conflict));
}

TEST_CASE("WithContext_PrefixesTheMessage_AndKeepsTheKind") {
  auto r = lookUpWithContext(false);
  REQUIRE_FALSE(r);
  CHECK((r.error().kind == ErrorKind::NotFound));
  CHECK(r.error().message == "lesson 'inner_ear': no structure 'stapes'");
  CHECK(lookUpWithContext(true).value() == 7);
}

TEST_CASE("ErrorKind_Names_AreDistinct") {
  const ErrorKind all[] = {ErrorKind::Invalid, ErrorKind::NotFound, ErrorKind::Conflict,
                           ErrorKind::Io,      ErrorKind::Unavailable, ErrorKind::Cancelled};
  for (ErrorKind a : all)
    for (ErrorKind b : all)
      if (a != b) CHECK(std::string(toString(a)) != toString(b));
  CHECK(std::string(toString(ErrorKind::NotFound)) == "not found");
}

TEST_CASE("StringHelpers_EdgeCases") {
  CHECK(str::lower("Cochlea.NII.GZ") == "cochlea.nii.gz");
  CHECK(str::trim("  \t cochlea \r\n") == "cochlea");
  CHECK(str::trim(" \t\r\n") == "");
  CHECK(str::trim("") == "");
  CHECK(str::startsWith("--db", "--"));
  CHECK_FALSE(str::startsWith("-", "--"));
  CHECK(str::endsWith("ct.nii.gz", ".nii.gz"));
  CHECK_FALSE(str::endsWith("gz", ".nii.gz"));
  CHECK(str::identifier("Vertebrae L1") == "vertebrae_l1");
  CHECK(str::identifier("kidney-left (2)") == "kidney_left_2");
  CHECK(str::identifier("__My Preset!__") == "my_preset");
  CHECK(str::identifier("***") == "");
  CHECK(str::join({"a", "b", "c"}, ", ") == "a, b, c");
  CHECK(str::join({}, ", ") == "");
}
