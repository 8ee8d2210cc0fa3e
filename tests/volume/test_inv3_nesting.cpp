// main.plist nesting is checked before libplist parses it (libplist recurses once per level): a
// few kilobytes nested 200,000 levels deep, XML or binary, or a binary plist that contains
// itself, are one-line errors in this process rather than a stack overflow.
#include <doctest/doctest.h>

#include "inv3_test_files.h"
#include "test_support.h"
#include "volume/inv3_io.h"

using namespace at;
using namespace at::test;

TEST_CASE("Inv3_DeeplyNestedMainPlist_IsRefusedBeforeParsing") {
  TempDir dir;
  const std::string matrix = inv3Matrix();
  const struct {
    const char* file;
    std::string plist;
    const char* mention;
  } cases[] = {
      {"deep-xml.inv3", deepXmlPlist(60000), "nests more than 64 levels"},
      {"deep-binary.inv3", deepBinaryPlist(100000), "nests more than 64 levels"},
      // The 200,000 levels: more bytes than a project header may hold.
      {"deeper-xml.inv3", deepXmlPlist(200000), "too many for a project header"},
      {"deeper-binary.inv3", deepBinaryPlist(200000), "too many for a project header"},
      {"cycle-binary.inv3", deepBinaryPlist(3, true), "contains itself"},
      {"truncated-binary.inv3", deepBinaryPlist(100).substr(0, 300), "damaged binary property list"},
  };
  for (const auto& c : cases) {
    INFO(std::string(c.file));
    writeTar(dir / c.file, {{"p/main.plist", c.plist}, {"p/matrix.dat", matrix}});
    auto loaded = loadInv3((dir / c.file).string());
    REQUIRE_FALSE(loaded);
    INFO(loaded.error().message);
    CHECK(loaded.error().message.find(c.mention) != std::string::npos);
    CHECK(loaded.error().message.find("main.plist") != std::string::npos);
  }
  // Within the limit the plist is parsed as before (and refused for its content, not its depth).
  writeTar(dir / "shallow.inv3", {{"p/main.plist", deepXmlPlist(40)}, {"p/matrix.dat", matrix}});
  auto shallow = loadInv3((dir / "shallow.inv3").string());
  REQUIRE_FALSE(shallow);
  CHECK(shallow.error().message.find("nests") == std::string::npos);
  writeInv3(dir / "real.inv3");
  CHECK(loadInv3((dir / "real.inv3").string()));
}
