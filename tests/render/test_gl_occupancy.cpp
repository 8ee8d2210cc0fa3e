// The renderer's empty-space grid after a selection change (a hover): adding the structure to the
// cached structure-free grid (withStructure) must give exactly the grid computed from scratch, and
// skipping with it must keep the image of marching every sample.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdlib>
#include <random>

#include "occupancy.h"
#include "render/gl/volume_renderer.h"
#include "render/gradient_volume.h"
#include "render/render_settings.h"
#include "render_fixture.h"
#include "test_support.h"
#include "volume/phantom.h"

using namespace at;
using namespace at::render;

TEST_CASE("Adding a structure to the structure-free occupancy grid equals computing the grid with it") {
  const Dataset ds = makePhantom({64, 51.2, 1});
  const GradientVolume gradients = computeGradientVolume(ds.volume);
  const gl::BlockSummary blocks = gl::summariseBlocks(ds.volume, ds.labels, gradients);
  REQUIRE(!blocks.blocksOfLabel.empty());
  std::mt19937_64 rng(test::freshSeed("occupancy with structure"));
  Preset wdt;
  wdt.mode = RenderMode::Wdt;
  const TransferFunction2D table = shadingTable(wdt);
  const gl::TableVisibility visibility(table);
  for (bool context : {false, true}) {
    gl::OccupancyInputs in;
    in.blocks = &blocks;
    in.volumeGrid = &ds.volume.geometry;
    in.table = context ? &visibility : nullptr;
    in.surfaceLo = wdt.surfaceGradientHu[0];
    std::vector<std::uint8_t> free = gl::computeOccupancy(in);
    gl::addLeapDistances(blocks.blocks, free);
    std::vector<std::uint16_t> labels{0, 999};  // none, and a label no block holds
    for (const Structure& s : ds.structures) labels.push_back(s.label);
    std::shuffle(labels.begin(), labels.end(), rng);
    for (std::uint16_t label : labels) {
      CAPTURE(context);
      CAPTURE(label);
      in.selected = label;
      std::vector<std::uint8_t> reference = gl::computeOccupancy(in);
      gl::addLeapDistances(blocks.blocks, reference);
      CHECK(gl::withStructure(blocks, free, label) == reference);
    }
  }
}

TEST_CASE("Leap distances are the capped Chebyshev distances to the nearest occupied block") {
  // Brute force over every block of random grids: sparse, clustered and empty ones, cubes and
  // odd shapes (the leap code pads and scans in raster order; the reference knows none of that).
  std::mt19937_64 rng(test::freshSeed("leap distances"));
  const Dims shapes[] = {{1, 1, 1}, {7, 5, 3}, {16, 16, 16}, {33, 9, 20}, {40, 1, 40}};
  for (const Dims& nb : shapes)
    for (double density : {0.0, 0.002, 0.02, 0.3}) {
      CAPTURE(nb.toString());
      CAPTURE(density);
      std::bernoulli_distribution occupied(density);
      std::vector<std::uint8_t> occ(nb.count(), 0);
      for (auto& v : occ) v = occupied(rng) ? (occupied(rng) ? gl::kOccupiedContext : gl::kOccupiedStructure) : 0;
      std::vector<std::uint8_t> expected = occ;
      for (int k = 0; k < nb.z; ++k)
        for (int j = 0; j < nb.y; ++j)
          for (int i = 0; i < nb.x; ++i) {
            std::uint8_t& e = expected[nb.index(i, j, k)];
            if (e & 3) continue;
            int best = gl::kMaxLeapBlocks;
            for (int c = 0; c < nb.z; ++c)
              for (int b = 0; b < nb.y; ++b)
                for (int a = 0; a < nb.x; ++a)
                  if (occ[nb.index(a, b, c)] & 3) best = std::min(best, std::max({std::abs(a - i), std::abs(b - j), std::abs(c - k)}));
            e = std::uint8_t(std::max(best, 1) << 2);
          }
      gl::addLeapDistances(nb, occ);
      CHECK(occ == expected);
    }
}

TEST_CASE("Skipping keeps the image when the selection moves from structure to structure") {
  auto* renderer = test::glRenderer();
  if (!renderer) return;
  const Dataset ds = makePhantom({64, 51.2, 1});
  REQUIRE(renderer->setVolume(ds.volume, ds.labels));
  REQUIRE(renderer->setField(FloatVolume(ds.volume.geometry, 0.0f)));
  std::size_t compared = 0;
  for (RenderMode mode : {RenderMode::Bare, RenderMode::Wdt}) {
    for (const Structure& s : ds.structures) {
      renderer->setSelected(s.label);
      RenderSettings settings;
      settings.width = 48;
      settings.height = 40;
      settings.preset.mode = mode;
      settings.camera = Camera::named(NamedView::Anterior, {0, 0, 0}, 30);
      CAPTURE(int(mode));
      CAPTURE(s.id);
      settings.skipEmptySpace = true;
      auto skipping = renderer->render(settings);
      REQUIRE_MESSAGE(skipping, skipping.error().message);
      settings.skipEmptySpace = false;
      auto every = renderer->render(settings);
      REQUIRE(every);
      int worst = 0;
      for (std::size_t i = 0; i < every->rgba.size(); ++i)
        worst = std::max(worst, std::abs(int(every->rgba[i]) - int(skipping->rgba[i])));
      CHECK(worst <= 1);
      ++compared;
    }
  }
  CHECK(compared >= 8);
}

TEST_CASE("Labels edited in a box and uploaded by that box give the blocks and the image of labels uploaded whole") {
  const Dataset ds = makePhantom({64, 51.2, 1});
  const Structure& moved = ds.structures.front();
  const Structure& other = ds.structures.back();
  // The edit: `moved` loses its voxels in one corner region and gains a slab elsewhere, over
  // `other`'s voxels too; the changed voxels lie in the box.
  LabelMap edited = ds.labels;
  const Dims& d = edited.dims();
  std::array<int, 6> box{d.x, d.y, d.z, 0, 0, 0};
  const auto change = [&](int i, int j, int k, std::uint16_t label) {
    std::uint16_t& v = edited.voxels[d.index(i, j, k)];
    if (v == label) return;
    v = label;
    const int at[3] = {i, j, k};
    for (std::size_t a = 0; a < 3; ++a) {
      box[a] = std::min(box[a], at[a]);
      box[a + 3] = std::max(box[a + 3], at[a] + 1);
    }
  };
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const std::uint16_t v = ds.labels.voxels[d.index(i, j, k)];
        if (v == moved.label && i < d.x / 2) change(i, j, k, 0);
        if (i >= 40 && i < 46 && j >= 20 && j < 44 && k >= 22 && k < 30) change(i, j, k, moved.label);
        if (v == other.label && k < d.z / 3) change(i, j, k, moved.label);
      }
  REQUIRE(box[3] > box[0]);
  const GradientVolume gradients = computeGradientVolume(ds.volume);
  gl::BlockSummary updated = gl::summariseBlocks(ds.volume, ds.labels, gradients);
  gl::updateBlockLabels(updated, edited, box);
  const gl::BlockSummary whole = gl::summariseBlocks(ds.volume, edited, gradients);
  CHECK(updated.labels == whole.labels);
  CHECK(updated.blocksOfLabel == whole.blocksOfLabel);

  auto* renderer = test::glRenderer();
  if (!renderer) return;
  RenderSettings settings;
  settings.width = 48;
  settings.height = 40;
  settings.camera = Camera::named(NamedView::Anterior, {0, 0, 0}, 30);
  for (RenderMode mode : {RenderMode::Bare, RenderMode::Wdt}) {
    CAPTURE(int(mode));
    settings.preset.mode = mode;
    // Edited after a first image (mask and grid built for the old labels) …
    REQUIRE(renderer->setVolume(ds.volume, ds.labels, gradients));
    REQUIRE(renderer->setField(FloatVolume(ds.volume.geometry, 0.0f)));
    renderer->setSelected(moved.label);
    REQUIRE(renderer->render(settings));
    REQUIRE(renderer->updateLabels(edited, box));
    auto byBox = renderer->render(settings);
    REQUIRE_MESSAGE(byBox, byBox.error().message);
    // … equals the edited labels uploaded whole.
    REQUIRE(renderer->setVolume(ds.volume, edited, gradients));
    REQUIRE(renderer->setField(FloatVolume(ds.volume.geometry, 0.0f)));
    renderer->setSelected(moved.label);
    auto fresh = renderer->render(settings);
    REQUIRE(fresh);
    CHECK(byBox->rgba == fresh->rgba);
    // And the edit shows: the image differs from the unedited one.
    REQUIRE(renderer->setVolume(ds.volume, ds.labels, gradients));
    REQUIRE(renderer->setField(FloatVolume(ds.volume.geometry, 0.0f)));
    renderer->setSelected(moved.label);
    auto before = renderer->render(settings);
    REQUIRE(before);
    CHECK(before->rgba != fresh->rgba);
  }
  // Labels on another grid are refused.
  CHECK_FALSE(renderer->updateLabels(LabelMap(Geometry{{8, 8, 8}, {1, 1, 1}}, 0), {0, 0, 0, 8, 8, 8}));
}
