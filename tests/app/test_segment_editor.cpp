// The desktop's segment editor: its controller on the phantom with the labels hidden (seeds painted
// voxel by voxel as clicks in slices paint them, grown, compared with the phantom's labels), the
// slice picture at the voxels' aspect with seeds drawn, and the UI-script actions driving the same
// commands headless (label, slice, seed, grow, undo, redo, save; bad seeds ending the script with one
// message).
#include <doctest/doctest.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <optional>
#include <thread>

#include "db/connection.h"
#include "headless_desktop.h"
#include "segment/local_threshold.h"
#include "segment/seeds.h"
#include "segment_editor/segment_controller.h"
#include "stroke_seeds.h"
#include "test_support.h"
#include "volume/nifti_io.h"

using namespace at;
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::array<int, 3> voxelOf(const Dims& d, std::size_t index) {
  return {int(index % std::size_t(d.x)), int(index / std::size_t(d.x) % std::size_t(d.y)),
          int(index / (std::size_t(d.x) * std::size_t(d.y)))};
}

// The voxel of `label` farthest inside it along x (a click well inside the structure).
std::array<int, 3> insideVoxel(const Dataset& ds, std::uint16_t label) {
  const Dims d = ds.labels.dims();
  std::size_t best = 0;
  int bestRun = -1;
  for (std::size_t i = 0; i < ds.labels.voxels.size(); ++i) {
    if (ds.labels.voxels[i] != label) continue;
    const auto v = voxelOf(d, i);
    int run = 0;
    while (v[0] - run - 1 >= 0 && v[0] + run + 1 < d.x && ds.labels.at(v[0] - run - 1, v[1], v[2]) == label &&
           ds.labels.at(v[0] + run + 1, v[1], v[2]) == label)
      ++run;
    if (run > bestRun) bestRun = run, best = i;
  }
  return voxelOf(d, best);
}

// Frames until the controller's growth is applied (at most a minute).
void waitForGrowth(app::SegmentController& editor) {
  for (int i = 0; i < 6000 && editor.growing(); ++i) {
    editor.poll();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  REQUIRE_FALSE(editor.growing());
}

std::vector<json> eventsNamed(const std::vector<json>& events, const std::string& name) {
  std::vector<json> out;
  for (const json& e : events)
    if (e.value("event", "") == name) out.push_back(e);
  return out;
}

// The phantom of `size` with its labels hidden (they are the reference), in a segment controller
// whose events are kept.
struct EditorOnPhantom {
  test::TempDir dir;
  db::Connection database;
  const Dataset& reference;
  Dataset unlabelled;
  std::vector<json> events;
  app::SegmentController editor;
  explicit EditorOnPhantom(int size)
      : database(openDatabase(dir)),
        reference(test::phantomOfSize(size)),
        unlabelled(withoutLabels(reference)),
        editor(database, [this](json e) { events.push_back(std::move(e)); }) {
    editor.attach(unlabelled);
  }
  static db::Connection openDatabase(const test::TempDir& dir) {
    auto opened = db::openDatabase((dir / "t.db").string());
    REQUIRE_MESSAGE(opened, test::errorText(opened));
    return std::move(*opened);
  }
  static Dataset withoutLabels(const Dataset& dataset) {
    Dataset out = dataset;
    out.labels = LabelMap();
    out.structures.clear();
    return out;
  }
};

}  // namespace

TEST_CASE("the segment controller grows seeds painted in slices into the phantom's structures") {
  EditorOnPhantom f(128);
  const Dataset& reference = f.reference;
  app::SegmentController& editor = f.editor;
  std::vector<json>& events = f.events;
  CHECK(editor.structures().empty());
  CHECK(editor.index() == 64);

  // One label per reference structure, seeds as the stroke rule draws them, painted voxel by voxel.
  const segment::SeedSet strokes = test::strokesInsideLabels(reference);
  auto raster = segment::rasteriseSeeds(strokes, reference.volume.geometry);
  REQUIRE(raster);
  std::map<std::uint16_t, std::uint16_t> editorLabel{{0, 0}};
  for (const Structure& s : reference.structures) {
    auto added = editor.addLabel(s.id);
    REQUIRE_MESSAGE(added, test::errorText(added));
    editorLabel[s.label] = *added;
  }
  CHECK_FALSE(editor.addLabel("cochlea"));     // names are unique
  CHECK_FALSE(editor.addLabel("Background"));  // 0 is the background
  editor.brushMm = 0;
  for (const GrowthSeed& seed : raster->seeds) {
    REQUIRE(editor.setCurrentLabel(editorLabel.at(seed.label)));
    REQUIRE(editor.paintSeeds(voxelOf(reference.volume.dims(), seed.index)));
  }
  CHECK(editor.seedCount() == raster->seeds.size());
  auto grown = editor.grow();
  REQUIRE_MESSAGE(grown, test::errorText(grown));
  CHECK(editor.growing());  // grow() returned; the growth runs on the editor's worker
  waitForGrowth(editor);
  REQUIRE_FALSE(editor.growError());
  events = eventsNamed(events, "segment_grown");
  REQUIRE(events.size() == 1);

  std::map<std::uint16_t, std::size_t> inReference, inGrown, inBoth;
  for (std::size_t i = 0; i < reference.labels.voxels.size(); ++i) {
    const std::uint16_t r = editorLabel.at(reference.labels.voxels[i]), g = editor.labels().voxels[i];
    ++inReference[r], ++inGrown[g];
    if (r == g) ++inBoth[r];
  }
  for (const Structure& s : reference.structures) {
    const std::uint16_t l = editorLabel[s.label];
    const double dice = 2.0 * double(inBoth[l]) / double(inReference[l] + inGrown[l]);
    CAPTURE(s.id);
    CAPTURE(dice);
    CHECK(events[0]["voxels"][s.id] == inGrown[l]);
    if (inReference[l] > 5000) CHECK(dice >= 0.85);  // the large cavities and vessels at 0.4 mm
  }

  // Undo brings back the unlabelled map; the slice picture follows.
  const std::uint64_t before = editor.revision();
  auto undone = editor.undo();
  REQUIRE(undone);
  CHECK(editor.revision() != before);
  CHECK(std::all_of(editor.labels().voxels.begin(), editor.labels().voxels.end(), [](std::uint16_t v) { return v == 0; }));
}

TEST_CASE("grow asked again while a growth runs: only the growth with the latest seeds is applied") {
  EditorOnPhantom f(96);
  const Dataset& reference = f.reference;
  app::SegmentController& editor = f.editor;
  std::vector<json>& events = f.events;
  const Dims d = reference.volume.dims();
  editor.brushMm = 0;
  REQUIRE(editor.paintSeeds({1, 1, 1}));  // background
  REQUIRE(editor.addLabel("first"));
  const std::uint16_t cochlea = reference.findStructure("cochlea")->label;
  REQUIRE(editor.paintSeeds(insideVoxel(reference, cochlea)));
  REQUIRE(editor.grow());
  // Before any frame takes the first growth: a third label's seed, and grow again.
  REQUIRE(editor.growing());
  auto second = editor.addLabel("second");
  REQUIRE(second);
  REQUIRE(editor.paintSeeds({d.x - 2, d.y - 2, d.z - 2}));
  REQUIRE(editor.grow());
  waitForGrowth(editor);
  REQUIRE_FALSE(editor.growError());
  CHECK(eventsNamed(events, "segment_growing").size() == 2);
  const auto grown = eventsNamed(events, "segment_grown");
  REQUIRE(grown.size() == 1);  // the first growth was not applied
  CHECK(grown[0]["voxels"]["second"].get<std::size_t>() > 0);
  CHECK(std::count(editor.labels().voxels.begin(), editor.labels().voxels.end(), *second) > 0);
  // One edit: a single undo returns to the unlabelled map.
  REQUIRE(editor.undo());
  CHECK(std::all_of(editor.labels().voxels.begin(), editor.labels().voxels.end(), [](std::uint16_t v) { return v == 0; }));
}

TEST_CASE("the segment editor's threshold island, margin and hollow work on the current structure") {
  EditorOnPhantom f(64);
  const Dataset& reference = f.reference;
  app::SegmentController& editor = f.editor;
  std::vector<json>& events = f.events;
  const auto count = [&](std::uint16_t label) {
    return std::size_t(std::count(editor.labels().voxels.begin(), editor.labels().voxels.end(), label));
  };
  // The background is not a structure for these tools.
  auto refused = editor.margin(1.0);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().message.find("not the background") != std::string::npos);
  auto bone = editor.addLabel("bone");
  REQUIRE(bone);
  // Bone of the phantom: the island above 300 HU under its densest voxel.
  const auto densest = std::max_element(reference.volume.voxels.begin(), reference.volume.voxels.end());
  const auto inside = voxelOf(reference.volume.dims(), std::size_t(densest - reference.volume.voxels.begin()));
  REQUIRE(reference.intensity.valueOf(*densest) > 300);
  auto island = editor.thresholdIsland(inside, 300, 4000, 0);
  REQUIRE_MESSAGE(island, test::errorText(island));
  const std::size_t islandVoxels = count(*bone);
  CHECK(islandVoxels > 100);
  CHECK(eventsNamed(events, "segment_edited").back()["tool"] == "threshold");
  // Outside the range: one message naming the value.
  auto air = editor.thresholdIsland({0, 0, 0}, 300, 4000, 0);
  REQUIRE_FALSE(air);
  CHECK(air.error().message.find("outside") != std::string::npos);
  // Margin: grown by 1 mm there are more voxels, shrunk back fewer; hollow keeps a shell.
  REQUIRE(editor.margin(1.0));
  const std::size_t grownVoxels = count(*bone);
  CHECK(grownVoxels > islandVoxels);
  REQUIRE(editor.margin(-1.0));
  const std::size_t shrunkVoxels = count(*bone);
  CAPTURE(islandVoxels);
  CAPTURE(grownVoxels);
  CAPTURE(shrunkVoxels);
  CHECK(shrunkVoxels < grownVoxels);
  REQUIRE(editor.hollow(0.5));
  CHECK(count(*bone) < shrunkVoxels);
  CHECK(count(*bone) > 0);
  CHECK(eventsNamed(events, "segment_edited").back()["tool"] == "hollow");
}

TEST_CASE("undo then redo gives the same labels and structures bit for bit; a new edit clears what could be redone") {
  EditorOnPhantom f(64);
  const Dataset& reference = f.reference;
  app::SegmentController& editor = f.editor;
  CHECK_FALSE(editor.canUndo());
  CHECK_FALSE(editor.canRedo());
  auto nothing = editor.redo();
  REQUIRE_FALSE(nothing);
  CHECK(nothing.error().message == "nothing to redo");
  auto bone = editor.addLabel("bone");  // an edit of the structure list
  REQUIRE(bone);
  const auto densest = std::max_element(reference.volume.voxels.begin(), reference.volume.voxels.end());
  const auto inside = voxelOf(reference.volume.dims(), std::size_t(densest - reference.volume.voxels.begin()));
  REQUIRE(editor.thresholdIsland(inside, 300, 4000, 0));
  REQUIRE(editor.margin(1.0));
  const LabelMap edited = editor.labels();
  const std::vector<Structure> structures = editor.structures();
  REQUIRE(std::count(edited.voxels.begin(), edited.voxels.end(), *bone) > 100);

  // All the way back: the unlabelled map, no structures (the current label falls back to 0).
  for (int i = 0; i < 3; ++i) REQUIRE(editor.undo());
  CHECK_FALSE(editor.canUndo());
  CHECK(editor.canRedo());
  CHECK(editor.structures().empty());
  CHECK(editor.currentLabel() == 0);
  CHECK(std::all_of(editor.labels().voxels.begin(), editor.labels().voxels.end(), [](std::uint16_t v) { return v == 0; }));
  // And forward again: the very same voxels and structures.
  for (int i = 0; i < 3; ++i) {
    const std::uint64_t before = editor.revision();
    auto redone = editor.redo();
    REQUIRE_MESSAGE(redone, test::errorText(redone));
    CHECK(editor.revision() != before);
  }
  CHECK_FALSE(editor.canRedo());
  CHECK(editor.labels().voxels == edited.voxels);
  REQUIRE(editor.structures().size() == structures.size());
  CHECK(editor.structures()[0].id == structures[0].id);
  CHECK(eventsNamed(f.events, "segment_undone").size() == 3);
  const auto redoneEvents = eventsNamed(f.events, "segment_redone");
  REQUIRE(redoneEvents.size() == 3);
  CHECK(redoneEvents.back()["edit"].get<std::string>().find("grow 'bone' by 1 mm") == 0);

  // Undo the margin, then a new edit (hollow): the margin can no longer be redone.
  REQUIRE(editor.undo());
  CHECK(editor.canRedo());
  REQUIRE(editor.setCurrentLabel(*bone));
  REQUIRE(editor.hollow(0.5));
  CHECK_FALSE(editor.canRedo());
  auto refused = editor.redo();
  REQUIRE_FALSE(refused);
  CHECK((refused.error().kind == ErrorKind::NotFound));
  CHECK(editor.labels().voxels != edited.voxels);
}

TEST_CASE("the segment editor's slice is shown at the voxels' aspect, with seeds drawn where they were painted") {
  test::TempDir dir;
  auto database = db::openDatabase((dir / "t.db").string());
  REQUIRE(database);
  Geometry g;
  g.dims = {40, 30, 10};
  g.spacingMm = {0.5, 0.5, 3.0};
  Dataset ds;
  ds.id = "aniso";
  ds.volume = Volume(g, 0);
  ds.labels = LabelMap(g, 0);
  app::SegmentController editor(*database, [](json) {});
  editor.attach(ds);
  REQUIRE(editor.showAxis(1));  // coronal: columns along x (0.5 mm), rows along z (3 mm)
  CHECK(editor.index() == 15);
  const auto pixelMm = editor.slicePixelMm();
  CHECK(pixelMm[0] == doctest::Approx(0.5));
  CHECK(pixelMm[1] == doctest::Approx(3.0));
  editor.brushMm = 0;
  REQUIRE(editor.paintSeeds({7, 15, 2}));
  auto image = editor.sliceImage(2);
  REQUIRE(image);
  CHECK(image->width == 80);
  CHECK(image->height == 20);
  // Row 0 is the highest z: voxel z = 2 is row 10 - 1 - 2 = 7; background seeds are white.
  const std::uint8_t* seed = image->pixel(7 * 2, 7 * 2);
  CHECK(seed[0] == 255);
  CHECK(image->pixel(0, 0)[0] < 255);
  CHECK(editor.voxelAtPixel(2, 7 * 2 + 1, 7 * 2 + 1) == std::array<int, 3>{7, 15, 2});
  CHECK_FALSE(editor.setSlice(1, 30));  // outside 0 … 29
  CHECK_FALSE(editor.paintSeeds({40, 0, 0}));
  // One label only: grow says what is missing.
  auto grown = editor.grow();
  REQUIRE_FALSE(grown);
  CHECK(grown.error().message.find("two or more labels") != std::string::npos);
}

TEST_CASE("UI script: segment_* actions label the phantom, undo, export, and refuse bad seeds with one message") {
  test::TempDir dir;
  const Dataset& phantom = test::phantomOfSize(64);
  const std::uint16_t cavityLabel = phantom.findStructure("tympanic_cavity")->label;
  const auto inside = insideVoxel(phantom, cavityLabel);
  const fs::path out = dir / "labels.nii.gz";
  json actions = json::array({
      {{"do", "segment_open"}},
      {{"do", "segment_label"}, {"name", "middle ear space"}},
      {{"do", "segment_slice"}, {"axis", "z"}, {"index", inside[2]}},
      {{"do", "segment_seed"}, {"voxel", inside}, {"brush_mm", 0.5}},
      {{"do", "segment_label"}, {"name", "background"}},
      {{"do", "segment_seed"}, {"voxel", {1, 1, 1}}},
      {{"do", "segment_seed"}, {"voxel", {62, 62, 62}}},
      // A large background dab limited to air values (a local threshold); later clicks are not.
      {{"do", "segment_seed"}, {"voxel", {1, 1, 1}}, {"brush_mm", 4.0}, {"low", -1100}, {"high", -400}},
      {{"do", "segment_grow"}},
      {{"do", "segment_undo"}},
      {{"do", "segment_grow"}},
      {{"do", "segment_undo"}},
      {{"do", "segment_redo"}},
      {{"do", "segment_save"}, {"out", out.string()}, {"names", (dir / "names.json").string()}},
  });
  test::HeadlessOptions options;
  options.dataset = "phantom:64";
  options.db = dir / "t.db";
  auto run = test::runHeadless({{"actions", actions}}, options);
  CAPTURE(run.messages);
  REQUIRE(run.exitCode == 0);
  const auto grown = test::eventsOf(run, "segment_grown");
  REQUIRE(grown.size() == 2);
  // The phantom's own structures are in the editor too; the new label grew from its seed.
  CHECK(grown[1]["voxels"]["middle_ear_space"].get<std::size_t>() > 100);
  CHECK(test::eventsOf(run, "segment_undone").size() == 2);
  CHECK(test::eventsOf(run, "segment_redone").size() == 1);  // the file below holds the redone growth
  REQUIRE(test::eventsOf(run, "segment_saved").size() == 1);
  auto written = loadNifti(out.string());
  REQUIRE_MESSAGE(written, test::errorText(written));
  CHECK(written->image.dims().toString() == phantom.labels.dims().toString());
  // The file holds what was grown: as many voxels of the new label as the event reported.
  const auto labelEvents = test::eventsOf(run, "segment_label");
  REQUIRE(labelEvents.size() == 2);
  const float newLabel = labelEvents[0]["label"].get<float>();
  CHECK(std::size_t(std::count(written->image.voxels.begin(), written->image.voxels.end(), newLabel)) ==
        grown[1]["voxels"]["middle_ear_space"].get<std::size_t>());
  CHECK(fs::exists(dir / "names.json"));

  // A seed outside the volume ends the script (status 2) with one message naming the voxel.
  json bad = json::array({{{"do", "segment_seed"}, {"voxel", {64, 0, 0}}}});
  run = test::runHeadless({{"actions", bad}}, options);
  CHECK(run.exitCode == 2);
  CHECK(run.messages.find("voxel (64, 0, 0) is outside the volume") != std::string::npos);
  // A seed range needs both ends, and the value under the voxel in it.
  bad = json::array({{{"do", "segment_seed"}, {"voxel", {1, 1, 1}}, {"low", -1100}}});
  run = test::runHeadless({{"actions", bad}}, options);
  CHECK(run.exitCode == 2);
  CHECK(run.messages.find("\"low\" and \"high\" go together") != std::string::npos);
  bad = json::array({{{"do", "segment_seed"}, {"voxel", {1, 1, 1}}, {"low", 300}, {"high", 3000}}});
  run = test::runHeadless({{"actions", bad}}, options);
  CHECK(run.exitCode == 2);
  CHECK(run.messages.find("is outside 300 … 3000") != std::string::npos);
  // Redo with nothing undone: one message.
  bad = json::array({{{"do", "segment_redo"}}});
  run = test::runHeadless({{"actions", bad}}, options);
  CHECK(run.exitCode == 2);
  CHECK(run.messages.find("nothing to redo") != std::string::npos);
  // Storing needs an imported dataset.
  bad = json::array({{{"do", "segment_save"}}});
  run = test::runHeadless({{"actions", bad}}, options);
  CHECK(run.exitCode == 2);
  CHECK(run.messages.find("not an imported dataset") != std::string::npos);
}

TEST_CASE("the segment editor's split islands: two painted blobs of one structure become two structures, one undo") {
  EditorOnPhantom t(64);
  app::SegmentController& editor = t.editor;
  auto label = editor.addLabel("two blobs");
  REQUIRE(label);
  editor.tool = app::SegmentController::Tool::Paint;
  editor.brushMm = 1.5;
  REQUIRE(editor.brushAtVoxel({12, 12, 12}));
  REQUIRE(editor.brushAtVoxel({50, 50, 50}));
  const LabelMap before = editor.labels();
  auto split = editor.splitIslands(0, 1);
  REQUIRE_MESSAGE(split, split.error().message);
  REQUIRE(split->newLabels.size() == 1);
  REQUIRE(editor.labelNamed("two blobs (2)"));
  CHECK(*editor.labelNamed("two blobs (2)") == split->newLabels[0]);
  const Dims d = editor.labels().dims();
  CHECK(editor.labels().voxels[d.index(12, 12, 12)] != editor.labels().voxels[d.index(50, 50, 50)]);
  const auto edited = eventsNamed(t.events, "segment_edited");
  REQUIRE(!edited.empty());
  CHECK(edited.back()["tool"] == "split_islands");
  CHECK(edited.back()["voxels"]["two_blobs"].get<std::size_t>() > 0);
  // Now one piece each: splitting again is an error naming the structure; undo restores both.
  auto again = editor.splitIslands(0, 1);
  REQUIRE_FALSE(again);
  CHECK(again.error().message.find("'two blobs' has 1 piece(s)") != std::string::npos);
  REQUIRE(editor.undo());
  CHECK(editor.labels().voxels == before.voxels);
  CHECK_FALSE(editor.labelNamed("two blobs (2)"));
}

TEST_CASE("the segment editor's seeds in range: a large background dab in the air beside bone seeds only the air") {
  EditorOnPhantom f(64);
  app::SegmentController& editor = f.editor;
  const Volume& volume = f.reference.volume;
  const Dims d = volume.dims();
  editor.brushMm = 3.0;
  // An air voxel with bone within the brush: the first such voxel in index order.
  std::optional<std::array<int, 3>> click;
  for (int k = 4; k < d.z - 4 && !click; ++k)
    for (int j = 4; j < d.y - 4 && !click; ++j)
      for (int i = 4; i < d.x - 4 && !click; ++i) {
        if (volume.voxels[d.index(i, j, k)] > -900) continue;
        for (int dk = -1; dk <= 1 && !click; ++dk)
          for (int dj = -1; dj <= 1 && !click; ++dj)
            for (int di = -1; di <= 1 && !click; ++di)
              if (volume.voxels[d.index(i + di, j + dj, k + dk)] > 600) click = {i, j, k};
      }
  REQUIRE(click);
  const auto whole = editor.paintSeeds(*click);  // the current label is the background
  REQUIRE(whole);
  editor.clearSeeds();
  editor.seedRange = {{-1100, -400}};
  const auto air = editor.paintSeeds(*click);
  REQUIRE(air);
  const auto expected = segment::localThresholdRegion(volume, f.unlabelled.intensity, *click, 3.0, -1100, -400);
  REQUIRE(expected);
  CHECK(*air == expected->size());
  CHECK(*air < *whole);
  CHECK(editor.seedsPerLabel().at(0) == *air);
  // A click on a value outside the range is refused and seeds nothing.
  editor.seedRange = {{500, 3000}};
  const auto refused = editor.paintSeeds(*click);
  REQUIRE_FALSE(refused);
  CHECK(refused.error().message.find("outside") != std::string::npos);
  CHECK(editor.seedsPerLabel().at(0) == *air);
}

// Where seeds are painted the patient's sides must be where a radiologist expects them, whatever
// the file's voxel order: the editor's slice is the Slices window's patient picture (radiological),
// for LPS (DICOM), RAS and LAS (NIfTI) grids and a sagittally acquired one (voxel axes S, A, L).
TEST_CASE("the segment editor's slice is in patient orientation for any voxel order: right-anterior at the axial picture's top left") {
  test::TempDir dir;
  auto database = db::openDatabase((dir / "t.db").string());
  REQUIRE(database);
  struct Grid {
    const char* name;
    Mat3 direction;
  };
  Mat3 ras, las, sagittal;
  ras.m = {{{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}}};
  las.m = {{{1, 0, 0}, {0, -1, 0}, {0, 0, 1}}};
  sagittal.m = {{{0, 0, 1}, {0, -1, 0}, {1, 0, 0}}};  // i → superior, j → anterior, k → left
  for (const Grid& grid : {Grid{"LPS", Mat3::identity()}, Grid{"RAS", ras}, Grid{"LAS", las}, Grid{"sagittal", sagittal}}) {
    CAPTURE(grid.name);
    Geometry g;
    g.dims = {24, 20, 16};
    g.spacingMm = {1.0, 1.5, 2.0};
    g.direction = grid.direction;
    Dataset ds;
    ds.id = "oriented";
    ds.volume = Volume(g, 0);
    // Distinct values so that two pictures agree only if they show the same voxels in one place.
    for (std::size_t v = 0; v < ds.volume.voxels.size(); ++v) ds.volume.voxels[v] = std::int16_t(-1000 + int(v % 2000));
    ds.labels = LabelMap(g, 0);
    app::SegmentController editor(*database, [](json) {});
    editor.attach(ds);
    // The voxel nearest the patient's right-anterior-superior corner (LPS: smallest x and y,
    // largest z) is a seed; its pixel lies in the top-left quadrant of the axial picture.
    std::size_t corner = 0;
    double best = 1e300;
    const Dims d = g.dims;
    for (int k = 0; k < d.z; ++k)
      for (int j = 0; j < d.y; ++j)
        for (int i = 0; i < d.x; ++i) {
          const Vec3 p = g.indexToPatient({double(i), double(j), double(k)});
          const double score = p[0] + p[1] - p[2];
          if (score < best) best = score, corner = d.index(i, j, k);
        }
    const std::array<int, 3> cornerVoxel{int(corner % std::size_t(d.x)), int(corner / std::size_t(d.x) % std::size_t(d.y)),
                                         int(corner / (std::size_t(d.x) * std::size_t(d.y)))};
    editor.brushMm = 0;
    REQUIRE(editor.paintSeeds(cornerVoxel));
    for (PatientPlane plane : {PatientPlane::Sagittal, PatientPlane::Coronal, PatientPlane::Axial}) {
      CAPTURE(planeName(plane));
      const int axis = editor.axisOfPlane(plane);
      REQUIRE(editor.setSlice(axis, cornerVoxel[std::size_t(axis)]));
      const SliceLayout layout = editor.sliceLayout();
      CHECK(layout.sliceAxis == axis);
      // The Slices window's picture of that plane, in the same grey window: the same pixels but the seed.
      SliceRequest request;
      request.layout = patientSliceLayout(g.direction, plane);
      request.index = cornerVoxel[std::size_t(axis)];
      request.scale = 2;
      request.windowCentreHu = editor.greyWindow()[0];
      request.windowWidthHu = editor.greyWindow()[1];
      const auto expected = renderSlice(ds.volume, nullptr, {}, request);
      const auto shown = editor.sliceImage(2, 0.0);
      REQUIRE(expected);
      REQUIRE(shown);
      REQUIRE(shown->width == expected->width);
      REQUIRE(shown->height == expected->height);
      std::size_t differing = 0;
      for (std::size_t b = 0; b < shown->rgb.size(); ++b) differing += shown->rgb[b] != expected->rgb[b];
      CHECK(differing <= 4 * 3);  // the seed's 2 × 2 pixels
      // The seed's pixel maps back to its voxel, and sits where the letters say.
      std::optional<std::pair<int, int>> seedPixel;
      for (int y = 0; y < shown->height && !seedPixel; ++y)
        for (int x = 0; x < shown->width && !seedPixel; ++x)
          if (shown->pixel(x, y)[0] == 255 && shown->pixel(x, y)[1] == 255 && shown->pixel(x, y)[2] == 255 &&
              expected->pixel(x, y)[0] != 255)
            seedPixel = std::pair{x, y};
      REQUIRE(seedPixel);
      CHECK(editor.voxelAtPixel(2, seedPixel->first + 0.5, seedPixel->second + 0.5) == cornerVoxel);
      const bool leftHalf = seedPixel->first < shown->width / 2, topHalf = seedPixel->second < shown->height / 2;
      if (plane == PatientPlane::Axial) {
        CHECK(layout.left == 'R');
        CHECK(layout.top == 'A');
        CHECK(leftHalf);
        CHECK(topHalf);
      } else if (plane == PatientPlane::Coronal) {
        CHECK(layout.left == 'R');
        CHECK(layout.top == 'S');
        CHECK(leftHalf);
        CHECK(topHalf);
      } else {
        CHECK(layout.left == 'A');
        CHECK(layout.top == 'S');
        CHECK(leftHalf);
        CHECK(topHalf);
      }
    }
  }
}

// The brush's 1.5 mm suits CT and a 0.1 mm µCT; on a finer µCT it keeps its voxels (a 10 µm µCT's
// brush is 0.15 mm), and a radius the user set follows from one dataset's scale to the next.
TEST_CASE("the segment editor's brush covers the same voxels on a uCT finer than 0.1 mm as at 0.1 mm") {
  EditorOnPhantom f(64);
  app::SegmentController& editor = f.editor;
  Dataset at100 = f.unlabelled, at10 = f.unlabelled;
  at100.volume.geometry.spacingMm = {0.1, 0.1, 0.1};
  at10.volume.geometry.spacingMm = {0.01, 0.01, 0.01};
  const auto dab = [&](const Dataset& dataset) {
    editor.attach(dataset);
    REQUIRE(editor.addLabel("bone"));
    const auto seeded = editor.paintSeeds({32, 32, 32});
    REQUIRE_MESSAGE(seeded, test::errorText(seeded));
    return *seeded;
  };
  CHECK(editor.brushMm == doctest::Approx(1.5));  // the 0.4 mm phantom: the CT default
  const std::size_t seeded100 = dab(at100);
  CHECK(editor.brushMm == doctest::Approx(1.5));
  CHECK(editor.brushScale() == doctest::Approx(1.0));
  const std::size_t seeded10 = dab(at10);
  CHECK(editor.brushMm == doctest::Approx(0.15));
  CHECK(editor.brushScale() == doctest::Approx(0.1));
  MESSAGE("a dab seeds " << seeded100 << " voxels at 0.1 mm, " << seeded10 << " at 0.01 mm");
  CHECK(seeded100 > 10000);  // a ball of 15 voxels' radius
  CHECK(std::abs(double(seeded100) - double(seeded10)) <= 0.01 * double(seeded100));
  editor.brushMm = 0.05;  // the user's 5 voxels on the 10 µm scan are 0.5 mm at 0.1 mm
  editor.attach(at100);
  CHECK(editor.brushMm == doctest::Approx(0.5));
  editor.attach(f.unlabelled);
  CHECK(editor.brushMm == doctest::Approx(0.5));
}
