// Imported datasets are opened by name by every dataset-taking command (datasets, structures,
// wdt, render), through the same resolver as the built-in phantom and plain paths.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include <fstream>

#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/nifti_io.h"
#include "volume/resample.h"

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

// A structure smaller than the volume's voxels, on a finer label map, is lost when the labels are
// resampled onto the volume: every command that reads the files says so on stderr in one line that
// names the label file and the structure, and `import` says it in its report; the other structures
// are kept and the import is stored.
TEST_CASE("LabelsLostToResampling_AreNamedByImportAndByEveryCommandOnTheFiles") {
  if (!test::requireSharedData("lost labels") || !test::requireAppBinary("lost labels")) return;
  const auto ts = test::sharedData("totalsegmentator");
  DatasetFiles files;
  files.volumePath = (ts / "ct_small.nii.gz").string();
  files.labelsPath = (ts / "seg_small.nii.gz").string();
  auto coarse = openDatasetFiles(files);
  REQUIRE(coarse);
  Geometry fine = coarse->labels.geometry;
  for (auto& s : fine.spacingMm) s /= 3;
  fine.dims = {fine.dims.x * 3, fine.dims.y * 3, fine.dims.z * 3};
  auto refined = resampleLabelsNearest(coarse->labels, fine);
  REQUIRE(refined);
  refined->at(181, 151, 46) = 300;  // one 1 mm voxel between the volume's 3 mm voxel centres
  test::TempDir dir;
  const std::string labels = (dir / "fine.nii.gz").string();
  REQUIRE(writeNiftiLabels(labels, *refined));
  nlohmann::json names = nlohmann::json::parse(test::readFile(ts / "labels.json"));
  names["300"] = "Nerve\x1b[2J";  // a hostile name: shown escaped
  std::ofstream(dir / "names.json") << names.dump();
  const std::string fileOptions = " --labels '" + labels + "' --names '" + (dir / "names.json").string() + "'";
  const std::string volume = "'" + files.volumePath + "'";
  const auto checkWarned = [&](const std::string& err) {
    CAPTURE(err);
    const std::string expected = "anatomy-tutor: warning: " + labels + ": 1 label lost every voxel";
    REQUIRE(err.find(expected) != std::string::npos);
    const std::string line = err.substr(err.find(expected), err.find('\n', err.find(expected)) - err.find(expected));
    CHECK(line.find("300 'Nerve\\x1b[2J' (1 voxel)") != std::string::npos);
    CHECK(line.find('\x1b') == std::string::npos);
  };
  const auto structures = test::runApp("structures " + volume + fileOptions);
  REQUIRE(structures.exitCode == 0);
  checkWarned(structures.err);
  CHECK(structures.out.find("liver") != std::string::npos);
  CHECK(structures.out.find("Nerve") == std::string::npos);
  const auto field = test::runApp("wdt " + volume + " liver --backend cpu --passes 1 --json" + fileOptions);
  REQUIRE(field.exitCode == 0);
  checkWarned(field.err);
  const std::string db = " --db '" + (dir / "t.db").string() + "'";
  const auto imported = test::runApp("import --volume " + volume + fileOptions + " --name fine" + db);
  REQUIRE(imported.exitCode == 0);
  CAPTURE(imported.out);
  CHECK(imported.out.find("  warning: " + labels + ": 1 label lost every voxel") != std::string::npos);
  const auto stored = test::runApp("structures fine" + db);
  REQUIRE(stored.exitCode == 0);
  CHECK(stored.out.find("liver") != std::string::npos);
}
