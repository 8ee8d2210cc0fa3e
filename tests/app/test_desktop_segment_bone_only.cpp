// The segment editor's growth settings and structure system in the desktop app under Xvfb, driven
// by the UI script as a user drives the Segment window: on an imported uint8 µCT (no HU, no
// labels), one seed in the skull's bone and one in the air grow a "bone" label that takes the
// soft tissue inside the skull too (no seed holds it, no edge stops it); the "bone" button
// ("bone only": the data's bone range) grows it again at once into bone voxels only; the system
// typed for it is stored with "Save into the dataset" and the command line lists it.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "dataset_resolver.h"
#include "desktop_script.h"
#include "segment/growth_settings.h"
#include "synthetic_scans.h"
#include "test_support.h"
#include "volume/nifti_io.h"
#include "volume/nrrd_io.h"

using namespace at;
using nlohmann::json;
namespace fs = std::filesystem;

TEST_CASE("desktop segment editor: 'bone only' grows a label of bone voxels and the structure's system is stored") {
  if (!test::requireXvfb()) return;
  test::TempDir dir("desktop-bone-only");
  const Dims dims{64, 56, 48};
  const FloatVolume uct = test::syntheticMicroCt(dims);
  const fs::path volume = dir / "skull_uct.nrrd", db = dir / "t.db", labels = dir / "labels.nii.gz";
  REQUIRE(writeNrrd(volume.string(), uct, ScalarKind::UInt8));
  auto imported = test::runApp("import --volume '" + volume.string() + "' --name uct --db '" + db.string() + "'");
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);

  // Bone intensity: above the midpoint of the soft tissue's and the bone's grey values.
  const test::MicroCtLayout layout = test::microCtLayout(dims);
  const float boneGrey = 0.5f * float(layout.brain + layout.bone);
  std::size_t boneVoxels = 0;
  for (float v : uct.voxels) boneVoxels += v >= boneGrey;
  // A voxel in the middle of the skull's top (the shell along +z), one in an air corner.
  const int ci = int(std::lround(layout.centre[0])), cj = int(std::lround(layout.centre[1]));
  const int ck = int(std::lround(layout.centre[2] + layout.radius[2] - 0.5 * layout.shell));
  REQUIRE(uct.at(ci, cj, ck) >= boneGrey);

  const json actions = json::array({
      {{"do", "segment_open"}},
      {{"do", "segment_label"}, {"name", "skull vault"}},
      {{"do", "segment_slice"}, {"axis", "z"}, {"index", ck}},
      {{"do", "segment_seed"}, {"voxel", {ci, cj, ck}}, {"brush_mm", 0.05}},
      {{"do", "segment_label"}, {"name", "background"}},
      {{"do", "segment_seed"}, {"voxel", {1, 1, 1}}, {"brush_mm", 0.05}},
      {{"do", "segment_grow"}},
      {{"do", "segment_growth"}, {"bone_only", true}},  // the "bone" button: grows again at once
      {{"do", "segment_system"}, {"name", "skull vault"}, {"system", "skull bones"}},
      {{"do", "segment_save"}},
      {{"do", "segment_save"}, {"out", labels.string()}},
  });
  test::DesktopOptions options;
  options.dataset = "uct";
  options.db = db;
  const test::DesktopRun run = test::runDesktopScript(dir, {{"actions", actions}}, options);
  INFO(run.err);
  REQUIRE(run.exitCode == 0);

  // Two growths: without the range the label holds the soft tissue inside the skull as well (more
  // voxels than all bone voxels together); with "bone only" it is grown again within the range.
  const auto grown = test::eventsOf(run, "segment_grown");
  REQUIRE(grown.size() == 2);
  const std::size_t before = grown[0]["voxels"]["skull_vault"].get<std::size_t>();
  const std::size_t after = grown[1]["voxels"]["skull_vault"].get<std::size_t>();
  CHECK(before > 3 * boneVoxels / 2);
  CHECK(after < before);
  const auto settings = test::eventsOf(run, "segment_growth_settings");
  REQUIRE(!settings.empty());
  const std::string lastSettings = settings.back().dump();
  CAPTURE(lastSettings);
  CHECK(settings.back()["range"].is_array());

  // The exported label: at least 85 % bone-intensity voxels, and most of the skull's bone.
  auto written = loadNifti(labels.string());
  REQUIRE_MESSAGE(written, test::errorText(written));
  REQUIRE(written->image.voxels.size() == uct.voxels.size());
  std::size_t inLabel = 0, bony = 0;
  for (std::size_t v = 0; v < uct.voxels.size(); ++v)
    if (written->image.voxels[v] > 0.5f) ++inLabel, bony += uct.voxels[v] >= boneGrey;
  CAPTURE(inLabel);
  CAPTURE(bony);
  CAPTURE(boneVoxels);
  REQUIRE(inLabel == after);
  CHECK(double(bony) >= 0.85 * double(inLabel));
  CHECK(double(bony) >= 0.5 * double(boneVoxels));

  // The system went into the dataset store with the labels: the command line lists it.
  auto listed = test::runApp("structures uct --json --db '" + db.string() + "'");
  REQUIRE_MESSAGE(listed.exitCode == 0, listed.err);
  const json structures = json::parse(listed.out);
  CAPTURE(listed.out);
  bool found = false;
  for (const json& s : structures.is_array() ? structures : structures.value("structures", json::array()))
    if (s.value("id", "") == "skull_vault") {
      found = true;
      CHECK(s.value("system", "") == "skull bones");
    }
  CHECK(found);
}

TEST_CASE("desktop segment editor: a label's own 'bone only' range is applied by the live growth, saved with the seeds, "
          "and grows the same labels reloaded and through `anatomy-tutor segment`") {
  if (!test::requireXvfb()) return;
  test::TempDir dir("desktop-label-range");
  const Dims dims{64, 56, 48};
  const FloatVolume uct = test::syntheticMicroCt(dims);
  const fs::path volume = dir / "skull_uct.nrrd", db = dir / "t.db", seeds = dir / "seeds.json";
  const fs::path plain = dir / "plain.nii.gz", first = dir / "first.nii.gz", reloaded = dir / "reloaded.nii.gz", cli = dir / "cli.nii.gz";
  REQUIRE(writeNrrd(volume.string(), uct, ScalarKind::UInt8));
  auto imported = test::runApp("import --volume '" + volume.string() + "' --name uct --db '" + db.string() + "'");
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  const test::MicroCtLayout layout = test::microCtLayout(dims);
  const float boneGrey = 0.5f * float(layout.brain + layout.bone);
  const int ci = int(std::lround(layout.centre[0])), cj = int(std::lround(layout.centre[1]));
  const int ck = int(std::lround(layout.centre[2] + layout.radius[2] - 0.5 * layout.shell));
  REQUIRE(uct.at(ci, cj, ck) >= boneGrey);
  // The data's bone range, as the editor derives it ("bone only").
  app::DatasetRequest request;
  request.name = volume.string();
  request.dbPath = db.string();
  auto opened = app::openNamedDataset(request);
  REQUIRE_MESSAGE(opened, test::errorText(opened));
  const double boneLow = segment::defaultGrowthSettings(opened->volume, opened->intensity).boneRangeValues[0];

  // The vault's seed in the bone, the background's in the air; one growth (the vault takes the soft
  // tissue inside the skull too), then the vault gets its own "bone only" range (grown again at once).
  test::DesktopOptions options;
  options.dataset = "uct";
  options.db = db;
  const json paint = json::array({
      {{"do", "segment_open"}},
      {{"do", "segment_label"}, {"name", "skull vault"}},
      {{"do", "segment_slice"}, {"axis", "z"}, {"index", ck}},
      {{"do", "segment_seed"}, {"voxel", {ci, cj, ck}}, {"brush_mm", 0.05}},
      {{"do", "segment_label"}, {"name", "background"}},
      {{"do", "segment_seed"}, {"voxel", {1, 1, 1}}, {"brush_mm", 0.05}},
      {{"do", "segment_grow"}},
      {{"do", "segment_save"}, {"out", plain.string()}},
      {{"do", "segment_label"}, {"name", "skull vault"}, {"grow_range", "bone"}},
      {{"do", "segment_grow"}},
      {{"do", "segment_seeds"}, {"save", seeds.string()}},
      {{"do", "segment_save"}, {"out", first.string()}},
  });
  const test::DesktopRun run = test::runDesktopScript(dir, {{"actions", paint}}, options);
  INFO(run.err);
  REQUIRE(run.exitCode == 0);
  const auto grown = test::eventsOf(run, "segment_grown");
  REQUIRE(grown.size() >= 2);
  const std::size_t unranged = grown.front()["voxels"]["skull_vault"].get<std::size_t>();
  const std::size_t ranged = grown.back()["voxels"]["skull_vault"].get<std::size_t>();
  CAPTURE(unranged);
  CAPTURE(ranged);
  REQUIRE(test::eventsOf(run, "segment_label_range").size() == 1);

  // The seeds file says so: the vault's label has "grow_range": "bone".
  const json saved = json::parse(std::ifstream(seeds));
  int rangedLabels = 0;
  for (const json& l : saved["labels"]) rangedLabels += l.contains("grow_range") && l["name"] == "skull_vault" && l["grow_range"] == "bone";
  CHECK(rangedLabels == 1);

  // Reloaded into a fresh desktop and grown, and grown by the command line: the same labels.
  const json reload = json::array({
      {{"do", "segment_open"}},
      {{"do", "segment_seeds"}, {"load", seeds.string()}},
      {{"do", "segment_grow"}},
      {{"do", "segment_save"}, {"out", reloaded.string()}},
  });
  const test::DesktopRun again = test::runDesktopScript(dir, {{"actions", reload}}, options);
  INFO(again.err);
  REQUIRE(again.exitCode == 0);
  auto cliRun = test::runApp("segment uct --seeds '" + seeds.string() + "' --backend cpu --out '" + cli.string() + "' --db '" +
                             db.string() + "'");
  REQUIRE_MESSAGE(cliRun.exitCode == 0, cliRun.err);
  auto a = loadNifti(first.string()), b = loadNifti(reloaded.string()), c = loadNifti(cli.string());
  auto p = loadNifti(plain.string());
  REQUIRE(p);
  REQUIRE(a);
  REQUIRE(b);
  REQUIRE(c);
  CHECK(a->image.voxels == b->image.voxels);
  CHECK(a->image.voxels == c->image.voxels);
  // The vault's label (its value in the seeds file) holds only voxels of the bone range now.
  std::uint16_t vault = 0;
  for (const json& l : saved["labels"])
    if (l["name"] == "skull_vault") vault = l["value"].get<std::uint16_t>();
  REQUIRE(vault != 0);
  std::size_t inVault = 0, soft = 0, inPlainVault = 0, plainSoft = 0;
  for (std::size_t v = 0; v < uct.voxels.size(); ++v) {
    if (std::lround(a->image.voxels[v]) == vault) ++inVault, soft += uct.voxels[v] < boneLow;
    if (std::lround(p->image.voxels[v]) == vault) ++inPlainVault, plainSoft += uct.voxels[v] < boneLow;
  }
  CAPTURE(plainSoft);
  REQUIRE(inPlainVault == unranged);
  REQUIRE(plainSoft > 0);  // the precondition: without its range the vault takes soft tissue
  CHECK(inVault == ranged);
  CHECK(soft == 0);
}
