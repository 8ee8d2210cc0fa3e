// Grow from seeds on the phantom with its labels removed: strokes drawn inside each structure and
// around it (tests/support/stroke_seeds.h: made from whatever labels the phantom has, so the test
// holds when the phantom is redesigned), a fraction of a per mille of the voxels. Every structure
// larger than 1000 voxels must reach Dice ≥ 0.90 against the phantom's labels; the table is printed.
#include <doctest/doctest.h>

#include <cstdio>
#include <map>

#include "segment/label_editor.h"
#include "segment/seeds.h"
#include "stroke_seeds.h"
#include "test_support.h"
#include "volume/dataset_source.h"

using namespace at;

TEST_CASE("Grow from seeds on the phantom: Dice >= 0.90 for every structure larger than 1000 voxels") {
  auto phantom = openBuiltinDataset("phantom");
  REQUIRE(phantom);
  const segment::SeedSet seeds = test::strokesInsideLabels(*phantom);
  auto raster = segment::rasteriseSeeds(seeds, phantom->volume.geometry);
  REQUIRE(raster);
  // The growth sees the volume and the seeds only; the labels are the reference.
  segment::LabelEditor editor(LabelMap(phantom->volume.geometry, 0), phantom->structures);
  GrowthParams params;  // the defaults: gradient weights over -1000 … 2000 HU, base 0.05
  params.backend = WdtBackend::Cpu;
  GrowthStats stats;
  auto grown = editor.growFromSeeds(phantom->volume, raster->seeds, params, &stats);
  REQUIRE(grown);
  const std::size_t total = phantom->volume.voxels.size();
  std::printf("phantom %s: %zu seed voxels (%.4f %% of %zu) in %zu strokes, %.0f ms on %s\n",
              phantom->volume.dims().toString().c_str(), raster->seeds.size(), 100.0 * double(raster->seeds.size()) / double(total),
              total, seeds.strokes.size(), stats.msTotal, stats.device.c_str());
  std::printf("%6s  %-30s %10s %10s %7s\n", "label", "structure", "reference", "grown", "Dice");
  std::map<std::uint16_t, std::size_t> reference, grownCount, both;
  for (std::size_t i = 0; i < total; ++i) {
    const std::uint16_t r = phantom->labels.voxels[i], g = editor.labels().voxels[i];
    ++reference[r], ++grownCount[g];
    if (r == g) ++both[r];
  }
  for (const Structure& s : phantom->structures) {
    const double dice = 2.0 * double(both[s.label]) / double(reference[s.label] + grownCount[s.label]);
    std::printf("%6u  %-30s %10zu %10zu %7.3f\n", unsigned(s.label), s.id.c_str(), reference[s.label],
                grownCount[s.label], dice);
    if (reference[s.label] > 1000) {
      CAPTURE(s.id);
      CHECK(dice >= 0.90);
    }
  }
}
