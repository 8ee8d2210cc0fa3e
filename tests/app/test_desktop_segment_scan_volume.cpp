// The desktop and the command line grow the same labels from the same seeds on a scan whose CT
// table the desktop leaves out of its pictures (services/scan_volumes.h): the desktop's segment
// editor grows on the scan as loaded, as `anatomy-tutor segment` does. Under Xvfb, driven by the
// UI script as a user drives the Segment window.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <random>
#include <string>

#include "dataset_resolver.h"
#include "desktop_script.h"
#include "scan_volumes.h"
#include "segment/growth_settings.h"
#include "segment/label_editor.h"
#include "segment/seeds.h"
#include "test_support.h"
#include "volume/nifti_io.h"
#include "volume/nrrd_io.h"

using namespace at;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

// A CT-like scan at 1 mm (int16, −1000 HU air): a soft-tissue body (40 HU) holding an organ of
// faint contrast (65 HU; noise sigma 20 HU everywhere), and below it, 6 mm of air apart, a CT
// table of noisy dense plastic (300 HU, sigma 150): not anatomy, so the desktop leaves it out of its
// pictures, and over it the data's step noise (hence the default base) differs. Fixed noise seed.
FloatVolume scanWithTable(const Dims& d) {
  Geometry g;
  g.dims = d;
  g.spacingMm = {1.0, 1.0, 1.0};
  FloatVolume v(g);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> noise(0.0, 1.0);
  const double cx = (d.x - 1) / 2.0, cy = 0.40 * d.y, cz = (d.z - 1) / 2.0;
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const double bx = (i - cx) / (0.42 * d.x), by = (j - cy) / (0.34 * d.y), bz = (k - cz) / (0.42 * d.z);
        const double ox = (i - cx + 0.1 * d.x) / 8.0, oy = (j - cy) / 7.0, oz = (k - cz) / 8.0;
        double hu = -1000, sigma = 5;
        if (bx * bx + by * by + bz * bz <= 1) hu = ox * ox + oy * oy + oz * oz <= 1 ? 65 : 40, sigma = 20;
        if (j >= int(0.40 * d.y + 0.34 * d.y) + 6 && j < d.y - 2) hu = 300, sigma = 150;
        v.at(i, j, k) = float(std::clamp(std::round(hu + sigma * noise(rng)), -1024.0, 3000.0));
      }
  return v;
}

}  // namespace

TEST_CASE("desktop segment editor and `anatomy-tutor segment` grow the same labels from the same seeds on a scan "
          "whose CT table the desktop leaves out of its pictures") {
  if (!test::requireXvfb()) return;
  test::TempDir dir("desktop-scan-volume");
  const Dims dims{64, 64, 40};
  const FloatVolume scan = scanWithTable(dims);
  const fs::path volume = dir / "ct_table.nrrd", db = dir / "t.db", seeds = dir / "seeds.json";
  const fs::path desktopLabels = dir / "desktop.nii.gz", cliLabels = dir / "cli.nii.gz";
  REQUIRE(writeNrrd(volume.string(), scan, ScalarKind::Int16));
  auto imported = test::runApp("import --volume '" + volume.string() + "' --name ct_table --db '" + db.string() + "'");
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);

  // The organ's centre, a voxel of the body's soft tissue away from it, and an air corner.
  const int cx = dims.x / 2 - int(0.1 * dims.x), cy = int(0.40 * dims.y), cz = dims.z / 2;
  const json actions = json::array({
      {{"do", "segment_open"}},
      {{"do", "segment_label"}, {"name", "organ"}},
      {{"do", "segment_slice"}, {"axis", "z"}, {"index", cz}},
      {{"do", "segment_seed"}, {"voxel", {cx, cy, cz}}, {"brush_mm", 2.0}},
      {{"do", "segment_label"}, {"name", "background"}},
      {{"do", "segment_seed"}, {"voxel", {cx + 22, cy, cz}}, {"brush_mm", 2.0}},
      {{"do", "segment_seed"}, {"voxel", {1, 1, 1}}, {"brush_mm", 1.0}},
      {{"do", "segment_grow"}},
      {{"do", "segment_seeds"}, {"save", seeds.string()}},
      {{"do", "segment_save"}, {"out", desktopLabels.string()}},
  });
  test::DesktopOptions options;
  options.dataset = "ct_table";
  options.db = db;
  const test::DesktopRun run = test::runDesktopScript(dir, {{"actions", actions}}, options);
  INFO(run.err);
  REQUIRE(run.exitCode == 0);
  REQUIRE(test::eventsOf(run, "segment_grown").size() == 1);
  const auto cliRun = test::runApp("segment ct_table --seeds '" + seeds.string() + "' --backend cpu --out '" +
                                   cliLabels.string() + "' --db '" + db.string() + "'");
  REQUIRE_MESSAGE(cliRun.exitCode == 0, cliRun.err);
  auto desktop = loadNifti(desktopLabels.string()), cli = loadNifti(cliLabels.string());
  REQUIRE(desktop);
  REQUIRE(cli);

  // The preconditions, so that the check below can fail: the desktop leaves the table out of the
  // volume it shows, and growing these seeds on that volume (with its own defaults, as the desktop
  // did before) gives other labels than on the scan as loaded.
  app::DatasetRequest request;
  request.name = "ct_table";
  request.dbPath = db.string();
  auto opened = app::openNamedDataset(request);
  REQUIRE_MESSAGE(opened, test::errorText(opened));
  Dataset shown = *opened;
  const app::ShownScan kept = app::leaveOutNonAnatomyForShowing(shown);
  REQUIRE(kept.asLoaded);
  REQUIRE(kept.leftOut > 0);
  CHECK(kept.asLoaded->voxels == opened->volume.voxels);
  CHECK(&kept.growthVolume(shown) == kept.asLoaded.get());
  auto set = segment::loadSeeds(seeds.string());
  REQUIRE(set);
  auto raster = segment::rasteriseSeeds(*set, shown.volume.geometry);
  REQUIRE(raster);
  const auto growOn = [&](const Volume& v) {
    GrowthParams params = segment::defaultGrowthSettings(v, shown.intensity).params;
    params.backend = WdtBackend::Cpu;
    segment::LabelEditor editor(LabelMap(v.geometry, 0), {});
    REQUIRE(editor.growFromSeeds(v, raster->seeds, params));
    return editor.labels();
  };
  const LabelMap onShown = growOn(shown.volume), onLoaded = growOn(opened->volume);
  std::size_t differ = 0;
  for (std::size_t v = 0; v < onShown.voxels.size(); ++v) differ += onShown.voxels[v] != onLoaded.voxels[v];
  MESSAGE(kept.leftOut << " voxels left out of the pictures; grown on them the labels would differ in " << differ
                       << " voxels");
  REQUIRE(differ > 0);

  // The check: the desktop's labels are the command line's, voxel for voxel (and the library's).
  REQUIRE(desktop->image.voxels.size() == cli->image.voxels.size());
  CHECK(desktop->image.voxels == cli->image.voxels);
  std::size_t differFromLoaded = 0;
  for (std::size_t v = 0; v < onLoaded.voxels.size(); ++v)
    differFromLoaded += std::lround(cli->image.voxels[v]) != long(onLoaded.voxels[v]);
  CHECK(differFromLoaded == 0);
}
