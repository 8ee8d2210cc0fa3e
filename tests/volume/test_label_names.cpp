// Label names from a JSON map { "value": "name" }.
#include <doctest/doctest.h>

#include "io_test_files.h"
#include "test_support.h"
#include "volume/image_file.h"

using namespace at;
using namespace at::test;

TEST_CASE("TotalSegmentator's labels.json maps its 117 label values to names") {
  if (!requireSharedData("labels.json")) return;
  auto names = loadLabelNames(sharedData("totalsegmentator/labels.json").string());
  REQUIRE_MESSAGE(names, names.error().message);
  CHECK(names->size() == 117);
  CHECK(names->at(1) == "spleen");
  CHECK(names->at(5) == "liver");
  CHECK(names->begin()->first == 1);
  CHECK(names->rbegin()->first == 117);
}

TEST_CASE("label names JSON problems are one-line errors naming the file") {
  TempDir dir;
  struct Case {
    const char* text;
    const char* expect;
  };
  const Case cases[] = {{"{ \"1\": \"liver\", ", "not valid JSON"},
                        {"[\"liver\"]", "expected a JSON object"},
                        {"{ \"one\": \"liver\" }", "\"one\" is not a label value"},
                        {"{ \"70000\": \"liver\" }", "\"70000\" is not a label value"},
                        {"{ \"-1\": \"liver\" }", "\"-1\" is not a label value"},
                        {"{ \"2\": 5 }", "label 2 is not a string"},
                        {"{ \"2\": 1e309 }", "line 1, column 13, field '2': number 1e309 is out of range"},
                        {"{ \"000000000000000000001\": \"x\" }", "is not a label value"}};
  int n = 0;
  for (const Case& c : cases) {
    CAPTURE(c.text);
    const auto path = dir / ("names" + std::to_string(n++) + ".json");
    writeBytes(path, c.text);
    auto names = loadLabelNames(path.string());
    REQUIRE_FALSE(names);
    CHECK(names.error().message.find(path.string()) == 0);
    CHECK(names.error().message.find(c.expect) != std::string::npos);
    CHECK(names.error().message.find('\n') == std::string::npos);
  }
  auto missing = loadLabelNames((dir / "absent.json").string());
  REQUIRE_FALSE(missing);
  CHECK(missing.error().message == (dir / "absent.json").string() + ": no such file");
}

TEST_CASE("a valid label names file with label 0 and large values loads every entry") {
  TempDir dir;
  writeBytes(dir / "names.json", "{ \"0\": \"background\", \"65535\": \"last\", \"12\": \"kidney\" }");
  auto names = loadLabelNames((dir / "names.json").string());
  REQUIRE(names);
  CHECK(names->size() == 3);
  CHECK(names->at(0) == "background");
  CHECK(names->at(65535) == "last");
  CHECK(names->at(12) == "kidney");
}
