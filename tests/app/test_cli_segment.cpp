// `anatomy-tutor segment` as an instructor uses it on a real scan nobody has labelled: hand-placed
// seed strokes (data/seeds/ct_small.json) on the TotalSegmentator CT, the label map written as NIfTI
// with names and as a Slicer .seg.nrrd, both read back by the app, stored into an imported dataset,
// and bad seeds refused with one line naming the problem.
#include <doctest/doctest.h>

#include <cstdio>
#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "cli_checks.h"
#include "test_support.h"

using namespace at;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

fs::path shippedSeeds(const std::string& name) { return fs::path(AT_SOURCE_DIR) / "data" / "seeds" / name; }

fs::path writeText(const test::TempDir& dir, const std::string& name, const std::string& text) {
  const fs::path path = dir / name;
  std::ofstream(path) << text;
  return path;
}

}  // namespace

TEST_CASE("segment on the real CT: seeds in liver, spleen, kidneys and L2 give Dice >= 0.85 against TotalSegmentator") {
  if (!test::requireSharedData("segment Dice on ct_small")) return;
  test::TempDir dir;
  const fs::path ts = test::sharedData("totalsegmentator");
  const fs::path out = dir / "grown.nii.gz";
  // --labels is the reference only: --compare reads it after the growth, which sees the CT and the
  // seeds (the labels of the output are the seeds file's).
  auto r = test::runApp("segment " + quoted(ts / "ct_small.nii.gz") + " --labels " + quoted(ts / "seg_small.nii.gz") +
                        " --seeds " + quoted(shippedSeeds("ct_small.json")) + " --backend cpu --compare --json --out " +
                        quoted(out));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  const json report = json::parse(r.out);
  CHECK(report["method"] == "grow");
  CHECK(report["seeded_fraction"].get<double>() < 0.01);  // strokes, not a labelling
  std::printf("ct_small (122x101x30, 3 mm), %zu seed voxels, %.0f ms on %s\n", report["seed_voxels"].get<std::size_t>(),
              report["ms"].get<double>(), report["growth"]["device"].get<std::string>().c_str());
  std::printf("%6s  %-16s %8s %10s %10s %7s\n", "label", "name", "seeds", "grown", "reference", "Dice");
  std::map<std::string, double> dice;
  for (const json& row : report["labels"]) {
    const std::string name = row["name"];
    dice[name] = row["dice"];
    std::printf("%6d  %-16s %8zu %10zu %10zu %7.3f\n", row["value"].get<int>(), name.c_str(),
                row["seed_voxels"].get<std::size_t>(), row["voxels"].get<std::size_t>(),
                row["reference_voxels"].get<std::size_t>(), dice[name]);
  }
  for (const char* name : {"liver", "spleen", "kidney_right", "kidney_left", "vertebrae_L2"}) {
    CAPTURE(name);
    REQUIRE(dice.count(name) == 1);
    CHECK(dice[name] >= 0.85);
  }
  // The output is a label map the app reads with the names written beside it.
  REQUIRE(fs::exists(out));
}

TEST_CASE("segment writes NIfTI + names and a Slicer .seg.nrrd that the app reads back, and stores labels into an imported dataset") {
  if (!test::requireSharedData("segment outputs on ct_small")) return;
  test::TempDir dir;
  const fs::path ts = test::sharedData("totalsegmentator");
  const std::string ct = quoted(ts / "ct_small.nii.gz"), seeds = " --seeds " + quoted(shippedSeeds("ct_small.json"));

  auto r = test::runApp("segment " + ct + seeds + " --backend cpu --out " + quoted(dir / "l.nii.gz") + " --names " +
                        quoted(dir / "l.json"));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  r = test::runApp("structures " + ct + " --labels " + quoted(dir / "l.nii.gz") + " --names " + quoted(dir / "l.json"));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  for (const char* id : {"spleen", "kidney_left", "kidney_right", "liver"}) CHECK(r.out.find(id) != std::string::npos);

  r = test::runApp("segment " + ct + seeds + " --backend cpu --out " + quoted(dir / "l.seg.nrrd"));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  const auto nrrdListing = test::runApp("structures " + ct + " --labels " + quoted(dir / "l.seg.nrrd"));
  REQUIRE_MESSAGE(nrrdListing.exitCode == 0, nrrdListing.err);
  // Same structures, same voxel counts, names from the segment metadata alone.
  const auto niftiListing = test::runApp("structures " + ct + " --labels " + quoted(dir / "l.nii.gz") + " --names " +
                                         quoted(dir / "l.json"));
  const auto body = [](const std::string& listing) { return listing.substr(listing.find('\n')); };
  CHECK(body(nrrdListing.out) == body(niftiListing.out));

  // Into the store: an imported CT without labels gets the grown ones, and every command sees them.
  const std::string db = " --db " + quoted(dir / "t.db");
  r = test::runApp("import --volume " + ct + " --name abdomen" + db);
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  r = test::runApp("segment abdomen" + seeds + " --backend cpu --save --out " + quoted(dir / "s.nii.gz") + db);
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("saved") != std::string::npos);
  r = test::runApp("structures abdomen" + db);
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(body(r.out) == body(niftiListing.out));
  // --save on something that is not an imported dataset changes nothing and says why.
  r = test::runApp("segment " + ct + seeds + " --backend cpu --save --out " + quoted(dir / "u.nii.gz") + db);
  test::checkOneLineError(r, "not an imported dataset");
}

TEST_CASE("segment refuses bad seeds and outputs with one line naming the problem, writing nothing") {
  test::TempDir dir;
  // The phantom's grid spans about ±25 mm around the origin.
  const std::string head = R"({"labels": [{"value": 0, "name": "background"}, {"value": 1, "name": "cochlea"}], "strokes": [)";
  const fs::path outside = writeText(dir, "outside.json", head + R"({"label": "cochlea", "points": [[0, 0, 0]]},
      {"label": "background", "points": [[900, 0, 0]]}]})");
  const fs::path oneLabel = writeText(dir, "one.json", head + R"({"label": "cochlea", "points": [[0, 0, 0], [1, 0, 0]]}]})");
  const fs::path unknown = writeText(dir, "unknown.json", head + R"({"label": "cochlea", "points": [[0, 0, 0]]},
      {"label": "kidney", "points": [[1, 1, 1]]}]})");
  const fs::path good = writeText(dir, "good.json", head + R"({"label": "cochlea", "points": [[0, 0, 0]]},
      {"label": 0, "points": [[5, 5, 5]]}]})");
  const fs::path out = dir / "x.nii.gz";
  const std::string base = "segment phantom:48 --backend cpu --out " + quoted(out) + " --seeds ";

  test::checkOneLineError(test::runApp(base + quoted(outside)), "strokes[1].points[0] (900.0, 0.0, 0.0) mm");
  test::checkOneLineError(test::runApp(base + quoted(outside)), "outside the volume");
  test::checkOneLineError(test::runApp(base + quoted(oneLabel)), "only label 'cochlea' has strokes");
  test::checkOneLineError(test::runApp(base + quoted(unknown)), "'kidney' is not one of the labels (background, cochlea)");
  test::checkOneLineError(test::runApp(base + quoted(dir / "missing.json")), "missing.json");
  test::checkOneLineError(test::runApp("segment phantom:48 --seeds " + quoted(good) + " --out " + quoted(dir / "x.png")),
                          "use a .nii, .nii.gz or .seg.nrrd file name");
  CHECK_FALSE(fs::exists(out));
  CHECK_FALSE(fs::exists(dir / "x.png"));
  // The good file works, and its dot seeds label the phantom's voxels around them.
  auto r = test::runApp(base + quoted(good) + " --json");
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  const json report = json::parse(r.out);
  CHECK(report["labels"][1]["name"] == "cochlea");
  CHECK(report["labels"][1]["voxels"].get<std::size_t>() > 0);
  CHECK(fs::exists(out));
}
