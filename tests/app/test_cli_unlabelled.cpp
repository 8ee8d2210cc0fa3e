// Scans nobody has labelled, opened as a new user would: a uint8 animal-skull µCT export
// (synthetic: the shared data has none) and an MR. info reads their intensities as such,
// structures/slice/render work on them without labels, the WDT says once that density-weighted
// distances on MR assume CT-like values, and the desktop shows the µCT whole and labels it.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <string>

#include "../volume/dicom_test_files.h"
#include "desktop_script.h"
#include "synthetic_scans.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/nifti_io.h"
#include "volume/nrrd_io.h"
#include "volume/png_image.h"

using namespace at;
using nlohmann::json;

namespace fs = std::filesystem;

namespace {

constexpr int kDesktopPanel = 320;  // the desktop's explore panel at UI scale 1 (the view lies right of it)

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

// A uint8 µCT export of the synthetic skull in `dir`.
fs::path writeMicroCt(const test::TempDir& dir, Dims dims = {72, 64, 56}) {
  const fs::path path = dir / "skull_uct.nrrd";
  REQUIRE(writeNrrd(path.string(), test::syntheticMicroCt(dims), ScalarKind::UInt8));
  return path;
}

double meanGrey(const RgbImage& image, int x0, int y0, int x1, int y1) {
  double sum = 0;
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x, ++n) sum += image.pixel(x, y)[0];
  return n ? sum / n : 0;
}

}  // namespace

TEST_CASE("info calls a uint8 µCT an image of plain intensities with a histogram window, not a label map") {
  test::TempDir dir;
  const fs::path uct = writeMicroCt(dir);
  auto r = test::runApp("info " + quoted(uct));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("kind:        image") != std::string::npos);
  CHECK(r.out.find("plain intensities") != std::string::npos);
  CHECK(r.out.find("label map") == std::string::npos);
  CHECK(r.out.find("labels:") == std::string::npos);
  r = test::runApp("info " + quoted(uct) + " --json");
  REQUIRE(r.exitCode == 0);
  const json j = json::parse(r.out);
  CHECK(j["kind"] == "image");
  CHECK(j["intensity"]["unit"] == "plain");
  const double lo = j["intensity"]["window"][0], hi = j["intensity"]["window"][1];
  const test::MicroCtLayout layout = test::microCtLayout({72, 64, 56});
  CHECK(lo <= layout.air + 5);
  CHECK(hi >= layout.bone - 10);
  // Forced to HU it is read as HU (the user's word wins).
  r = test::runApp("info " + quoted(uct) + " --intensity hu --json");
  REQUIRE(r.exitCode == 0);
  CHECK(json::parse(r.out)["intensity"]["unit"] == "HU");
  r = test::runApp("info " + quoted(uct) + " --intensity grey");
  CHECK(r.exitCode != 0);
  CHECK(r.err.find("grey") != std::string::npos);
}

TEST_CASE("structures, slice and render open an unlabelled µCT; the slice uses its window, not a HU one") {
  test::TempDir dir;
  const fs::path uct = writeMicroCt(dir);
  auto r = test::runApp("structures " + quoted(uct));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("72x64x56") != std::string::npos);

  const fs::path slice = dir / "slice.png";
  r = test::runApp("slice " + quoted(uct) + " --axis z --index 28 --out " + quoted(slice));
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  auto png = readPng(slice.string());
  REQUIRE(png);
  // Air in the corner dark, the skull's bone (on the ellipse, left of centre) bright: a HU window
  // (400 ± 1000) made both the same flat grey.
  const double air = meanGrey(*png, 0, 0, 4, 4);
  const test::MicroCtLayout layout = test::microCtLayout({72, 64, 56});
  const int boneX = int(layout.centre[0] - layout.radius[0] + layout.shell / 2), midY = int(layout.centre[1]);
  const double bone = meanGrey(*png, boneX - 1, midY - 1, boneX + 1, midY + 1);
  CHECK(air < 40);
  CHECK(bone > 150);

  const fs::path render = dir / "whole.png";
  r = test::runApp("render " + quoted(uct) + " --size 96x96 --view anterior --out " + quoted(render));
  if (r.exitCode != 0 && r.err.find("EGL") != std::string::npos) {
    at::test::skipf("render needs EGL (%s)", r.err.c_str());
    return;
  }
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("whole volume") != std::string::npos);
  png = readPng(render.string());
  REQUIRE(png);
  // The skull in the middle of the picture, the background around it.
  CHECK(meanGrey(*png, 40, 40, 56, 56) > meanGrey(*png, 0, 0, 8, 8) + 40);
  // A structure that the dataset does not have still says how to label it.
  r = test::runApp("render " + quoted(uct) + " cochlea --mode wdt --out " + quoted(render));
  CHECK(r.exitCode != 0);
  CHECK(r.err.find("no labelled structures") != std::string::npos);
}

TEST_CASE("the real 3 mm abdominal CT without labels renders its body and its bones, not a dark frame") {
  if (!test::requireSharedData("whole-volume render of ct_small")) return;
  test::TempDir dir;
  const fs::path ct = test::sharedData("totalsegmentator/ct_small.nii.gz"), out = dir / "abdomen.png";
  // From above: the body's cross-section, the spine and the ribs (30 slices of 3 mm).
  auto r = test::runApp("render " + quoted(ct) + " --view superior --size 200x200 --no-overlays --backend cpu --out " +
                        quoted(out));
  if (r.exitCode != 0 && r.err.find("EGL") != std::string::npos) {
    at::test::skipf("render needs EGL (%s)", r.err.c_str());
    return;
  }
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  CHECK(r.out.find("whole volume") != std::string::npos);
  auto png = readPng(out.string());
  REQUIRE(png);
  // Pixels brighter than the background (the body's outline and organs: the earlier data TF, with
  // its opacity spread over the whole volume, lit 0.1 % of them), and white ones (bone).
  int lit = 0, white = 0;
  for (int y = 0; y < png->height; ++y)
    for (int x = 0; x < png->width; ++x) {
      const std::uint8_t* p = png->pixel(x, y);
      lit += std::max({p[0], p[1], p[2]}) > 40;
      white += std::min({p[0], p[1], p[2]}) > 150;
    }
  const double litShare = double(lit) / (png->width * png->height);
  MESSAGE("ct_small whole volume from above: lit " << litShare << ", white pixels " << white);
  CHECK(litShare > 0.03);
  CHECK(white >= 8);
}

TEST_CASE("render DATASET --out without a structure draws the whole phantom, and rejects --mode") {
  test::TempDir dir;
  const fs::path out = dir / "phantom.png";
  auto r = test::runApp("render phantom:64 --size 64x64 --out " + quoted(out));
  if (r.exitCode != 0 && r.err.find("EGL") != std::string::npos) {
    at::test::skipf("render needs EGL (%s)", r.err.c_str());
    return;
  }
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  auto png = readPng(out.string());
  REQUIRE(png);
  CHECK(meanGrey(*png, 24, 24, 40, 40) > meanGrey(*png, 0, 0, 4, 4) + 40);
  r = test::runApp("render phantom:64 --mode wdt --out " + quoted(out));
  CHECK(r.exitCode != 0);
  CHECK(r.err.find("--mode needs a STRUCTURE") != std::string::npos);
}

TEST_CASE("wdt on an MR says once that density-weighted distances assume CT-like values") {
  if (!test::requireSharedData("wdt on MR")) return;
  test::TempDir dir;
  // The head series relabelled as MR (DICOM Modality), with a block of label 1 on its grid.
  const fs::path mr = dir / "mr";
  fs::create_directories(mr);
  for (const auto& entry : fs::directory_iterator(test::sharedData("headsq/dicom"))) {
    if (entry.path().extension() != ".dcm") continue;
    REQUIRE(test::rewriteDicom(entry.path(), mr / entry.path().filename(),
                               [](DcmDataset& d) { d.putAndInsertString(DCM_Modality, "MR"); }));
  }
  DatasetFiles files;
  files.volumePath = mr.string();
  auto head = openDatasetFiles(files);
  REQUIRE(head);
  REQUIRE(head->intensity.modality == "MR");
  LabelMap labels(head->volume.geometry, 0);
  for (int k = 40; k < 50; ++k)
    for (int j = 28; j < 36; ++j)
      for (int i = 28; i < 36; ++i) labels.at(i, j, k) = 1;
  const fs::path labelPath = dir / "block.nii.gz";
  REQUIRE(writeNiftiLabels(labelPath.string(), labels));
  const std::string wdt = "wdt " + quoted(mr) + " label_1 --labels " + quoted(labelPath) + " --backend cpu";
  auto r = test::runApp(wdt + " --json");
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  std::size_t notes = 0;
  for (std::size_t at = r.err.find("assume CT-like"); at != std::string::npos; at = r.err.find("assume CT-like", at + 1))
    ++notes;
  CHECK(notes == 1);
  // Uniform weights do not use the intensities: no note.
  r = test::runApp(wdt + " --weight uniform --json");
  REQUIRE(r.exitCode == 0);
  CHECK(r.err.find("assume CT-like") == std::string::npos);
}

TEST_CASE("the desktop opens an unlabelled µCT whole, with a data TF, and its segment editor grows labels on it") {
  if (!test::requireXvfb()) return;
  test::TempDir dir("desktop-unlabelled");
  const Dims dims{72, 64, 56};
  const fs::path uct = writeMicroCt(dir, dims);
  const test::MicroCtLayout layout = test::microCtLayout(dims);
  const json brainVoxel = {int(layout.centre[0]), int(layout.centre[1]), int(layout.centre[2])};
  // In the shell, on each axis both ways: half its thickness inside the outer surface.
  json skullSeeds = json::array();
  for (int axis = 0; axis < 3; ++axis)
    for (int side : {-1, 1}) {
      std::array<double, 3> v{layout.centre[0], layout.centre[1], layout.centre[2]};
      v[std::size_t(axis)] += side * (layout.radius[axis] - 0.5 * layout.shell);
      skullSeeds.push_back({{"do", "segment_seed"}, {"voxel", {int(std::lround(v[0])), int(std::lround(v[1])), int(std::lround(v[2]))}},
                            {"brush_mm", 0.05}});
    }

  const fs::path shot = dir / "whole.png";
  json script = {{"actions",
                        {{{"do", "view"}, {"value", "anterior"}},
                         {{"do", "wait_field"}},
                         {{"do", "segment_open"}},
                         {{"do", "segment_label"}, {"name", "brain"}},
                         {{"do", "segment_seed"}, {"voxel", brainVoxel}, {"brush_mm", 0.1}},
                         {{"do", "segment_label"}, {"name", "skull"}},
                         {{"do", "segment_label"}, {"name", "background"}},
                         {{"do", "segment_seed"}, {"voxel", {1, 1, 1}}, {"brush_mm", 0.15}},
                         {{"do", "segment_seed"}, {"voxel", {dims.x - 2, dims.y - 2, dims.z - 2}}},
                         {{"do", "segment_seed"}, {"voxel", {dims.x - 2, 1, dims.z - 2}}},
                         {{"do", "segment_seed"}, {"voxel", {1, dims.y - 2, 1}}},
                         {{"do", "segment_grow"}},
                         {{"do", "segment_open"}, {"open", false}}}}};  // the view uncovered for the screenshot
  // The skull's seeds right after its label is chosen.
  json& actions = script["actions"];
  const auto skull = std::find_if(actions.begin(), actions.end(), [](const json& a) { return a.value("name", "") == "skull"; });
  actions.insert(skull + 1, skullSeeds.begin(), skullSeeds.end());
  test::DesktopOptions options;
  options.dataset = uct.string();
  options.screenshot = shot.string();
  const auto run = test::runDesktopScript(dir, script, options);
  INFO(run.err);
  REQUIRE(run.exitCode == 0);
  CHECK(run.err.find("no labelled structures") == std::string::npos);

  // The whole volume fills the middle of the view; the corners are background.
  auto image = readPng(shot.string());
  REQUIRE(image);
  REQUIRE(image->width == 800);
  const int cx = kDesktopPanel + (800 - kDesktopPanel) / 2, cy = 240;
  int lit = 0;
  for (int y = 0; y < image->height; ++y)
    for (int x = kDesktopPanel; x < image->width; ++x) lit += image->pixel(x, y)[0] > 40;
  CHECK(lit > (800 - kDesktopPanel) * 480 / 10);
  CHECK(meanGrey(*image, cx - 30, cy - 30, cx + 30, cy + 30) > meanGrey(*image, kDesktopPanel + 4, 4, kDesktopPanel + 40, 40) + 40);

  // The editor labelled it: the brain seed grew to the inside of the shell (its ellipsoid's volume
  // within a quarter), not over the whole volume.
  const auto grown = test::eventsOf(run.events, "segment_grown");
  REQUIRE(grown.size() == 1);
  const double inner = 4.0 / 3.0 * M_PI * (layout.radius[0] - layout.shell) * (layout.radius[1] - layout.shell) *
                       (layout.radius[2] - layout.shell);
  const double brain = grown[0]["voxels"]["brain"].get<double>();
  CAPTURE(inner);
  CHECK(brain > 0.75 * inner);
  CHECK(brain < 1.25 * inner);
  CHECK(grown[0]["voxels"]["skull"].get<double>() > 0);
}
