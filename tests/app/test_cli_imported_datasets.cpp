// Imported datasets are opened by name by every dataset-taking command (datasets, structures,
// wdt, render), through the same resolver as the built-in phantom and plain paths.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include "test_support.h"

using namespace at;

TEST_CASE("ImportedDataset_IsListedAndOpensByNameInEveryCommand") {
  if (!test::requireSharedData("imported dataset commands")) return;
  test::TempDir dir;
  const std::string db = " --db '" + (dir / "t.db").string() + "'";
  const auto ts = test::sharedData("totalsegmentator");
  auto imported = test::runApp("import --volume '" + (ts / "ct_small.nii.gz").string() + "' --labels '" +
                               (ts / "seg_small.nii.gz").string() + "' --names '" + (ts / "labels.json").string() +
                               "' --name abdomen" + db);
  CAPTURE(imported.err);
  REQUIRE(imported.exitCode == 0);

  auto listed = test::runApp("datasets --json" + db);
  REQUIRE(listed.exitCode == 0);
  const auto list = nlohmann::json::parse(listed.out)["datasets"];
  bool found = false;
  for (const auto& d : list) found = found || (d["id"] == "abdomen" && d["builtin"] == false);
  CHECK(found);

  auto structures = test::runApp("structures abdomen" + db);
  CHECK(structures.exitCode == 0);
  CHECK(structures.out.find("liver") != std::string::npos);

  auto field = test::runApp("wdt abdomen liver --backend cpu --passes 2 --json" + db);
  CAPTURE(field.err);
  REQUIRE(field.exitCode == 0);
  const auto j = nlohmann::json::parse(field.out);
  CHECK(j["dataset"] == "abdomen");
  CHECK(j["dims"][0] == 122);

  auto unknown = test::runApp("structures pancreas_study" + db);
  CHECK(unknown.exitCode != 0);
  CHECK(unknown.err.find("imported: abdomen") != std::string::npos);
}
