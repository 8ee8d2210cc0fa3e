// The one JSON parser of the readers of outside JSON: every problem is an Error with line, column
// and field, nothing throws.
#include <doctest/doctest.h>

#include <string>

#include "core/json_document.h"
#include "core/regular_file.h"
#include "test_support.h"

using namespace at;

namespace {

std::string errorOf(const std::string& text) {
  auto j = parseJsonDocument(text, "doc.json");
  REQUIRE_FALSE(j);
  CHECK(j.error().message.find('\n') == std::string::npos);
  return j.error().message;
}

}  // namespace

TEST_CASE("JsonDocument_ValidDocuments_ParseAsNlohmannDoes") {
  const std::string text = R"({"a": [1, -2, 3.5, 18446744073709551615, "x", null, true, {"b": {}}], "c": []})";
  auto j = parseJsonDocument(text, "doc.json");
  REQUIRE(j);
  CHECK(*j == nlohmann::json::parse(text));
  CHECK(*parseJsonDocument("3", "n.json") == 3);
}

TEST_CASE("JsonDocument_NumbersBeyondADouble_AreErrorsNamingLineColumnAndField") {
  CHECK(errorOf("{\"a\": {\"b\": [0, 1e309]}}") ==
        "doc.json: line 1, column 22, field 'a.b[1]': number 1e309 is out of range (beyond ±1.8e308)");
  CHECK(errorOf("{\n  \"alpha\":\n    -1e400\n}") ==
        "doc.json: line 3, column 11, field 'alpha': number -1e400 is out of range (beyond ±1.8e308)");
  CHECK(errorOf("1e999") == "doc.json: line 1, column 6: number 1e999 is out of range (beyond ±1.8e308)");
  // A huge token is cut in the message.
  CHECK(errorOf("[1" + std::string(500, '0') + "e999]").size() < 200);
}

TEST_CASE("JsonDocument_SyntaxErrors_NameLineAndColumn") {
  CHECK(errorOf("{\"a\": 1,\n \"b\" 2}").find("doc.json: line 2, column 7, field 'b': not valid JSON: syntax error") == 0);
  CHECK(errorOf("").find("doc.json: line 1, column 1: not valid JSON") == 0);
  CHECK(errorOf("{} x").find("doc.json: line 1, column 5: not valid JSON") == 0);
  // Control characters of the input are quoted printably.
  CHECK(errorOf("[\"a\x1b[2J").find('\x1b') == std::string::npos);
}

TEST_CASE("JsonDocument_DeepNesting_IsRefusedNotRecursedInto") {
  CHECK(errorOf(std::string(100000, '[')).find("nested deeper than 256 levels") != std::string::npos);
  CHECK(parseJsonDocument(std::string(200, '[') + std::string(200, ']'), "ok.json"));
}

TEST_CASE("JsonDocument_Files_OnlyRegularOnesAreRead") {
  test::TempDir dir;
  CHECK(readJsonFile((dir / "absent.json").string(), "absent.json").error().message == "absent.json: no such file");
  CHECK((readJsonFile((dir / "absent.json").string(), "absent.json").error().kind == ErrorKind::NotFound));
  CHECK(readJsonFile(dir.path().string(), "dir").error().message == "dir: is a folder, not a file");
  CHECK(readJsonFile("/dev/zero", "zero").error().message == "zero: is a device, not a regular file");
}
