// The real skull CT in the desktop's segment editor (Xvfb, UI script): its kept seeds file
// (data/segmentations/skull/seeds.json: 873 k seed voxels, per-label ranges) grows the labels
// `anatomy-tutor segment` grows from it, voxel for voxel, though the desktop leaves the headrest
// out of its pictures; and after dabs over other labels' seeds (incremental updates that reset
// what grew from the relabelled seeds) the desktop's labels are the command line's growth of the
// seeds it saved.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

#include "dataset_resolver.h"
#include "desktop_script.h"
#include "scan_volumes.h"
#include "skull_scan.h"
#include "test_support.h"
#include "volume/nifti_io.h"

using namespace at;
using nlohmann::json;
namespace fs = std::filesystem;

TEST_CASE("desktop segment editor on the skull CT: the kept seeds grow the command line's labels, before and after dabs "
          "over other labels' seeds") {
  if (!test::requireXvfb()) return;
  const auto& cache = test::grownSkullCache();
  if (!cache) return;
  test::SkullCacheScope scope(*cache);
  test::TempDir dir("desktop-skull-segment");
  // The precondition: the desktop leaves voxels (the headrest) out of the skull it shows.
  app::DatasetRequest request;
  request.name = "skull";
  auto opened = app::openNamedDataset(request);
  REQUIRE_MESSAGE(opened, test::errorText(opened));
  Dataset shown = *opened;
  const app::ShownScan kept = app::leaveOutNonAnatomyForShowing(shown);
  REQUIRE(kept.asLoaded);
  MESSAGE(kept.leftOut << " voxels outside the body (the headrest among them) set to the background level for pictures");

  const fs::path first = dir / "first.nii.gz", edited = dir / "edited.nii.gz", editedSeeds = dir / "edited.json";
  const fs::path cliEdited = dir / "cli_edited.nii.gz";
  // (86, 137, 10) holds background seeds beside the left mandible; (182, 135, 0) Mandible seeds.
  const json actions = json::array({
      {{"do", "segment_open"}},
      {{"do", "segment_seeds"}, {"load", test::skullSeedsFile().string()}},
      {{"do", "segment_grow"}},
      {{"do", "segment_save"}, {"out", first.string()}},
      {{"do", "segment_label"}, {"name", "Mandible"}},
      {{"do", "segment_seed"}, {"voxel", {86, 137, 10}}, {"brush_mm", 1.0}},
      {{"do", "segment_grow"}},
      {{"do", "segment_label"}, {"name", "background"}},
      {{"do", "segment_seed"}, {"voxel", {182, 135, 0}}, {"brush_mm", 2.0}},
      {{"do", "segment_grow"}},
      {{"do", "segment_seeds"}, {"save", editedSeeds.string()}},
      {{"do", "segment_save"}, {"out", edited.string()}},
  });
  test::DesktopOptions options;
  options.dataset = "skull";
  const test::DesktopRun run = test::runDesktopScript(dir, {{"actions", actions}}, options);
  INFO(run.err);
  REQUIRE(run.exitCode == 0);
  const auto grown = test::eventsOf(run, "segment_grown");
  REQUIRE(grown.size() == 3);
  for (const json& g : grown) MESSAGE("segment_grown: incremental " << g["incremental"] << ", " << g["ms"] << " ms");

  const auto cliRun = test::runApp("segment skull --seeds '" + editedSeeds.string() + "' --method grow --backend cpu --out '" +
                                   cliEdited.string() + "'");
  REQUIRE_MESSAGE(cliRun.exitCode == 0, cliRun.err);
  auto desktopFirst = loadNifti(first.string()), desktopEdited = loadNifti(edited.string());
  auto cliFirst = loadNifti((*cache / "anatomy-tutor" / "scans" / "invesalius-examples" / "skull.labels.nii.gz").string());
  auto cliAfter = loadNifti(cliEdited.string());
  REQUIRE(desktopFirst);
  REQUIRE(desktopEdited);
  REQUIRE(cliFirst);
  REQUIRE(cliAfter);
  CHECK(desktopFirst->image.voxels == cliFirst->image.voxels);
  CHECK(desktopEdited->image.voxels == cliAfter->image.voxels);
  CHECK(desktopEdited->image.voxels != desktopFirst->image.voxels);  // the dabs changed labels
}
