// The desktop's segment editor (its controller, headless): seeds painted in slices, grown, saved as
// a seeds file and loaded into a fresh editor grow the same labels bit for bit; the growth's
// settings start from the data (a plain-intensity scan gets its histogram window, not the HU
// one), are checked, and a change after a growth grows again (the live preview).
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <thread>

#include "db/connection.h"
#include "growth_measures.h"
#include "segment/seeds.h"
#include "segment_editor/segment_controller.h"
#include "dataset_resolver.h"
#include "test_support.h"
#include "volume/image_file.h"
#include "volume/nrrd_io.h"

using namespace at;
using nlohmann::json;

namespace {

void waitForGrowth(app::SegmentController& editor) {
  for (int i = 0; i < 6000 && editor.growing(); ++i) {
    editor.poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  REQUIRE_FALSE(editor.growing());
  REQUIRE_FALSE(editor.growError());
}

db::Connection openDatabase(const test::TempDir& dir) {
  auto opened = db::openDatabase((dir / "t.db").string());
  REQUIRE_MESSAGE(opened, test::errorText(opened));
  return std::move(*opened);
}

// The µCT-like volume (uint8 plain intensities, 0.1 mm) without its labels.
Dataset unlabelledMicroCt() {
  Dataset ds = test::makeMicroCt(64, 0.1, 4.0, 7).dataset;
  ds.labels = LabelMap();
  ds.structures.clear();
  return ds;
}

// Seeds as an instructor paints them: brush dabs of two structures and the background.
void paintSeeds(app::SegmentController& editor, const Dims& d) {
  editor.brushMm = 0.25;
  REQUIRE(editor.paintSeeds({2, 2, d.z / 2}));
  REQUIRE(editor.paintSeeds({d.x - 3, d.y - 3, d.z / 2}));
  REQUIRE(editor.addLabel("upper"));
  REQUIRE(editor.paintSeeds({d.x / 2, d.y / 2, d.z / 2}));
  REQUIRE(editor.paintSeeds({d.x / 2 + 4, d.y / 2, d.z / 2}));
  REQUIRE(editor.addLabel("lower"));
  REQUIRE(editor.paintSeeds({d.x / 2, d.y / 2, d.z / 4}));
}

}  // namespace

TEST_CASE("seeds painted in the segment editor, saved and loaded into a fresh editor, grow the same labels") {
  test::TempDir dir;
  db::Connection database = openDatabase(dir);
  const Dataset ds = unlabelledMicroCt();
  const Dims d = ds.volume.dims();
  app::SegmentController first(database, [](json) {});
  first.attach(ds);
  paintSeeds(first, d);
  REQUIRE(first.grow());
  waitForGrowth(first);
  const LabelMap grown = first.labels();
  CHECK(std::count(grown.voxels.begin(), grown.voxels.end(), std::uint16_t(1)) > 0);
  const std::string path = (dir / "seeds.json").string();
  REQUIRE(first.saveSeeds(path));

  // The file is an ordinary seeds file: it parses, names the labels, and rasterises onto the same
  // seed voxels.
  auto set = segment::loadSeeds(path);
  REQUIRE_MESSAGE(set, test::errorText(set));
  CHECK(set->labels.size() == 3);
  REQUIRE(set->grow.base);
  auto raster = segment::rasteriseSeeds(*set, ds.volume.geometry);
  REQUIRE(raster);
  CHECK(raster->seeds.size() == first.seedCount());
  CHECK(set->strokes.size() * 2 < first.seedCount());  // rows of voxels, not one dot per voxel

  std::vector<json> events;
  app::SegmentController second(database, [&](json e) { events.push_back(std::move(e)); });
  second.attach(ds);
  auto loaded = second.loadSeeds(path);
  REQUIRE_MESSAGE(loaded, test::errorText(loaded));
  CHECK(*loaded == first.seedCount());
  CHECK(second.seedsPerLabel() == first.seedsPerLabel());
  REQUIRE(second.structures().size() == 2);
  CHECK(second.growthSettings().basePerVoxel == doctest::Approx(first.growthSettings().basePerVoxel));
  REQUIRE(second.grow());
  waitForGrowth(second);
  CHECK(second.labels().voxels == grown.voxels);

  // A file that is not a seeds file: one error naming it, the painted seeds kept.
  const std::string bad = (dir / "bad.json").string();
  {
    std::ofstream out(bad);
    out << "{\"schema\": 1, \"labels\": 3}";
  }
  auto refused = second.loadSeeds(bad);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().message.find("bad.json") != std::string::npos);
  CHECK(second.seedCount() == first.seedCount());
}

TEST_CASE("the segment editor's growth settings come from the data, are checked, and a change grows again") {
  test::TempDir dir;
  db::Connection database = openDatabase(dir);
  const Dataset ds = unlabelledMicroCt();
  std::vector<json> events;
  app::SegmentController editor(database, [&](json e) { events.push_back(std::move(e)); });
  editor.attach(ds);
  // Plain intensities: the histogram window (uint8 values), not −1000 … 2000 HU; a base per voxel.
  const auto settings = editor.growthSettings();
  CHECK(settings.window[0] >= 0);
  CHECK(settings.window[1] <= 255);
  CHECK(settings.basePerVoxel > 0);
  CHECK(editor.growthParams().baseCost == doctest::Approx(settings.basePerVoxel / 0.1));

  auto bad = settings;
  bad.basePerVoxel = 0;
  auto refused = editor.setGrowthSettings(bad);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().message.find("base") != std::string::npos);
  bad = settings;
  bad.window = {200, 100};
  CHECK_FALSE(editor.setGrowthSettings(bad));
  CHECK(editor.growthSettings().basePerVoxel == settings.basePerVoxel);  // unchanged

  // Before any growth a change only sets; after one it grows again with the new settings.
  paintSeeds(editor, ds.volume.dims());
  auto changed = settings;
  changed.basePerVoxel = settings.basePerVoxel * 4;
  REQUIRE(editor.setGrowthSettings(changed));
  CHECK_FALSE(editor.growing());
  REQUIRE(editor.grow());
  waitForGrowth(editor);
  const LabelMap atFour = editor.labels();
  changed.basePerVoxel = settings.basePerVoxel / 4;
  REQUIRE(editor.setGrowthSettings(changed));
  CHECK(editor.growing());
  waitForGrowth(editor);
  CHECK(editor.labels().voxels != atFour.voxels);  // the preview shows the new settings' labels
  const auto grownEvents = std::count_if(events.begin(), events.end(),
                                         [](const json& e) { return e.value("event", "") == "segment_grown"; });
  CHECK(grownEvents == 2);
}

TEST_CASE("a seeds file's per-label grow ranges survive loading into the segment editor and saving again") {
  test::TempDir dir;
  db::Connection database = openDatabase(dir);
  const Dataset ds = unlabelledMicroCt();
  app::SegmentController first(database, [](json) {});
  first.attach(ds);
  paintSeeds(first, ds.volume.dims());
  const std::string painted = (dir / "painted.json").string();
  REQUIRE(first.saveSeeds(painted));

  // The instructor gives "upper" a range and "lower" the bone range in the file.
  json doc = json::parse(std::ifstream(painted));
  for (json& label : doc["labels"]) {
    if (label["name"] == "upper") label["grow_range"] = {40.0, 230.0};
    if (label["name"] == "lower") label["grow_range"] = "bone";
  }
  const std::string ranged = (dir / "ranged.json").string();
  std::ofstream(ranged) << doc.dump(2);

  std::vector<json> events;
  app::SegmentController second(database, [&](json e) { events.push_back(std::move(e)); });
  second.attach(ds);
  REQUIRE(second.loadSeeds(ranged));
  CHECK(second.status().find("2 labels grow only in their range") != std::string::npos);
  REQUIRE(!events.empty());
  CHECK(events.back()["labels_with_grow_range"] == 2);
  const std::string saved = (dir / "saved.json").string();
  REQUIRE(second.saveSeeds(saved));
  auto set = segment::loadSeeds(saved);
  REQUIRE_MESSAGE(set, test::errorText(set));
  int upper = 0, lower = 0, others = 0;
  for (const segment::SeedLabel& l : set->labels) {
    if (l.name == "upper") {
      ++upper;
      REQUIRE(l.growRange);
      CHECK((*l.growRange)[0] == doctest::Approx(40.0));
      CHECK((*l.growRange)[1] == doctest::Approx(230.0));
      CHECK_FALSE(l.growRangeBone);
    } else if (l.name == "lower") {
      ++lower;
      CHECK(l.growRangeBone);
    } else {
      others += l.hasGrowRange();
    }
  }
  CHECK(upper == 1);
  CHECK(lower == 1);
  CHECK(others == 0);

  // Attaching another dataset forgets them: its seeds are saved without ranges.
  second.attach(ds);
  paintSeeds(second, ds.volume.dims());
  REQUIRE(second.saveSeeds(saved));
  auto fresh = segment::loadSeeds(saved);
  REQUIRE(fresh);
  for (const segment::SeedLabel& l : fresh->labels) CHECK_FALSE(l.hasGrowRange());
}

namespace {

// How many voxels of `label` have a value outside `range` (the dataset's values).
std::size_t outsideRange(const Dataset& ds, const LabelMap& labels, std::uint16_t label, const std::array<double, 2>& range) {
  std::size_t outside = 0;
  for (std::size_t i = 0; i < labels.voxels.size(); ++i) {
    if (labels.voxels[i] != label) continue;
    const double value = ds.intensity.valueOf(ds.volume.voxels[i]);
    outside += value < range[0] || value > range[1];
  }
  return outside;
}

}  // namespace

TEST_CASE("the segment editor's live growth applies per-label grow ranges exactly as `anatomy-tutor segment --seeds` does") {
  test::TempDir dir;
  db::Connection database = openDatabase(dir);
  // The µCT-like volume as a uint8 NRRD file, opened the way the desktop and the command line open it.
  const Dataset micro = unlabelledMicroCt();
  FloatVolume image(micro.volume.geometry, 0.0f);
  for (std::size_t i = 0; i < image.voxels.size(); ++i) image.voxels[i] = float(micro.volume.voxels[i]);
  const std::string volumePath = (dir / "microct.nrrd").string();
  REQUIRE(writeNrrd(volumePath, image, ScalarKind::UInt8));
  app::DatasetRequest request;
  request.name = volumePath;
  request.dbPath = (dir / "none.db").string();
  auto ds = app::openNamedDataset(request);
  REQUIRE_MESSAGE(ds, test::errorText(ds));
  REQUIRE_FALSE(ds->intensity.hounsfield());

  std::vector<json> events;
  app::SegmentController editor(database, [&](json e) { events.push_back(std::move(e)); });
  editor.attach(*ds);
  paintSeeds(editor, ds->volume.dims());
  const std::uint16_t upper = *editor.labelNamed("upper"), lower = *editor.labelNamed("lower");
  REQUIRE(editor.grow());
  waitForGrowth(editor);
  const LabelMap plain = editor.labels();

  // "upper" grows only in the values of its own seed voxels; "lower" in the data's bone range.
  std::array<double, 2> upperRange{1e9, -1e9};
  {  // the seed voxels of "upper", through a saved seeds file
    const std::string painted = (dir / "painted.json").string();
    REQUIRE(editor.saveSeeds(painted));
    auto set = segment::loadSeeds(painted);
    REQUIRE(set);
    auto raster = segment::rasteriseSeeds(*set, ds->volume.geometry);
    REQUIRE(raster);
    for (const GrowthSeed& s : raster->seeds) {
      if (s.label != upper) continue;
      const double value = ds->intensity.valueOf(ds->volume.voxels[s.index]);
      upperRange = {std::min(upperRange[0], value - 1), std::max(upperRange[1], value + 1)};
    }
  }
  const std::array<double, 2> bone = editor.growthDefaults().boneRangeValues;
  // The precondition: unranged, both labels take voxels outside their ranges.
  REQUIRE(outsideRange(*ds, plain, upper, upperRange) > 0);
  REQUIRE(outsideRange(*ds, plain, lower, bone) > 0);

  // Setting a label's range grows again at once (the live preview); errors name the problem.
  REQUIRE(editor.setLabelGrowRange(upper, app::SegmentController::LabelGrowRange{upperRange, false}));
  CHECK(editor.growing());
  waitForGrowth(editor);
  REQUIRE(editor.setLabelGrowRange(lower, app::SegmentController::LabelGrowRange{std::nullopt, true}));
  waitForGrowth(editor);
  CHECK(events.back()["event"] == "segment_grown");
  const LabelMap ranged = editor.labels();
  CHECK(outsideRange(*ds, ranged, upper, upperRange) == 0);
  CHECK(outsideRange(*ds, ranged, lower, bone) == 0);
  const auto count = [](const LabelMap& m, std::uint16_t l) { return std::count(m.voxels.begin(), m.voxels.end(), l); };
  CHECK(count(ranged, upper) > 0);
  CHECK(count(ranged, lower) > 0);
  MESSAGE("upper " << count(plain, upper) << " -> " << count(ranged, upper) << " voxels, lower " << count(plain, lower)
                   << " -> " << count(ranged, lower) << " (bone from " << bone[0] << ")");
  CHECK_FALSE(editor.setLabelGrowRange(0, app::SegmentController::LabelGrowRange{std::nullopt, true}));
  CHECK_FALSE(editor.setLabelGrowRange(999, app::SegmentController::LabelGrowRange{std::nullopt, true}));
  auto inverted = editor.setLabelGrowRange(upper, app::SegmentController::LabelGrowRange{std::array<double, 2>{200, 100}, false});
  REQUIRE_FALSE(inverted);
  CHECK(inverted.error().message.find("low < high") != std::string::npos);
  CHECK_FALSE(editor.growing());

  // The command line grows the saved seeds file (ranges included) to the same labels, voxel for voxel.
  const std::string seedsPath = (dir / "ranged.json").string(), out = (dir / "cli.nii.gz").string();
  REQUIRE(editor.saveSeeds(seedsPath));
  const auto r = test::runApp("segment '" + volumePath + "' --seeds '" + seedsPath + "' --backend cpu --out '" + out + "'");
  REQUIRE_MESSAGE(r.exitCode == 0, r.err);
  auto loaded = loadImageFile(out);
  REQUIRE_MESSAGE(loaded, test::errorText(loaded));
  auto cli = toLabelMap(*loaded, out);
  REQUIRE(cli);
  CHECK(cli->voxels == ranged.voxels);

  // Cleared, the ranges no longer apply: the ordinary growth's labels come back.
  REQUIRE(editor.setLabelGrowRange(upper, std::nullopt));
  waitForGrowth(editor);
  REQUIRE(editor.setLabelGrowRange(lower, std::nullopt));
  waitForGrowth(editor);
  CHECK(editor.labels().voxels == plain.voxels);
}
