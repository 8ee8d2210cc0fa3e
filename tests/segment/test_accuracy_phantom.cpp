// Grow from seeds on the phantom with its labels removed: strokes drawn inside each structure and
// around it (tests/support/stroke_seeds.h: made from whatever labels the phantom has, so the test
// holds when the phantom is redesigned), a fraction of a per mille of the voxels. Every structure
// larger than 1000 voxels must reach Dice ≥ 0.90 against the phantom's labels; the table is printed.
//
// Thin structures are the exception the scan's resolution makes: where a structure is less than
// three voxels from its centre to its outside (the 0.55 mm facial nerve on 0.2 mm voxels), its
// outermost voxel shell is a quarter of its volume, and the scanner's blur (σ = 0.2 mm) over a
// cortical wall thinner than 2σ moves the steepest edge inwards by about that shell. A thin
// structure below 0.90 must still reach 0.80, and its disagreement must be that shell: at least
// 95 % of the wrongly labelled voxels within one voxel of the reference's surface.
#include <doctest/doctest.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "segment/distance_map.h"
#include "segment/label_editor.h"
#include "segment/seeds.h"
#include "stroke_seeds.h"
#include "test_support.h"
#include "volume/dataset_source.h"

using namespace at;

namespace {

// The fraction of the voxels where `grown` and `reference` disagree about `label` that lie within
// `toleranceMm` of the reference structure's surface (inside or outside it).
double disagreementNearSurface(const LabelMap& reference, const LabelMap& grown, std::uint16_t label, double toleranceMm) {
  Mask inside(reference.geometry, 0), outside(reference.geometry, 0);
  for (std::size_t v = 0; v < reference.voxels.size(); ++v) {
    inside.voxels[v] = reference.voxels[v] == label;
    outside.voxels[v] = !inside.voxels[v];
  }
  const FloatVolume toInside = segment::distanceToMask(inside), toOutside = segment::distanceToMask(outside);
  std::size_t wrong = 0, near = 0;
  for (std::size_t v = 0; v < reference.voxels.size(); ++v) {
    const bool r = reference.voxels[v] == label, g = grown.voxels[v] == label;
    if (r == g) continue;
    ++wrong;
    if ((r ? toOutside.voxels[v] : toInside.voxels[v]) <= toleranceMm) ++near;
  }
  return wrong ? double(near) / double(wrong) : 1.0;
}

}  // namespace

TEST_CASE("Grow from seeds on the phantom: Dice >= 0.90 for every structure larger than 1000 voxels") {
  auto phantom = openBuiltinDataset("phantom");
  REQUIRE(phantom);
  std::map<std::uint16_t, double> depthMm;
  const segment::SeedSet seeds = test::strokesInsideLabels(*phantom, {}, &depthMm);
  auto raster = segment::rasteriseSeeds(seeds, phantom->volume.geometry);
  REQUIRE(raster);
  // The growth sees the volume and the seeds only; the labels are the reference.
  segment::LabelEditor editor(LabelMap(phantom->volume.geometry, 0), phantom->structures);
  // Gradient weights over -1000 … 2000 HU, travel 0.05 per 0.2 mm voxel (base 0.25 per mm): with
  // dense strokes on both sides of every wall, distance should weigh about as much as a faint edge.
  GrowthParams params;
  params.baseCost = 0.25f;
  params.backend = WdtBackend::Cpu;
  GrowthStats stats;
  auto grown = editor.growFromSeeds(phantom->volume, raster->seeds, params, &stats);
  REQUIRE(grown);
  const std::size_t total = phantom->volume.voxels.size();
  const auto& spacing = phantom->volume.geometry.spacingMm;
  const double voxelMm = std::min({spacing[0], spacing[1], spacing[2]});
  std::printf("phantom %s (%.3f mm voxels): %zu seed voxels (%.4f %% of %zu) in %zu strokes, %.0f ms on %s\n",
              phantom->volume.dims().toString().c_str(), voxelMm, raster->seeds.size(), 100.0 * double(raster->seeds.size()) / double(total),
              total, seeds.strokes.size(), stats.msTotal, stats.device.c_str());
  std::printf("%6s  %-30s %10s %10s %7s %9s\n", "label", "structure", "reference", "grown", "Dice", "half-mm");
  std::map<std::uint16_t, std::size_t> reference, grownCount, both;
  for (std::size_t i = 0; i < total; ++i) {
    const std::uint16_t r = phantom->labels.voxels[i], g = editor.labels().voxels[i];
    ++reference[r], ++grownCount[g];
    if (r == g) ++both[r];
  }
  for (const Structure& s : phantom->structures) {
    const double dice = 2.0 * double(both[s.label]) / double(reference[s.label] + grownCount[s.label]);
    const bool thin = depthMm[s.label] < 3 * voxelMm;
    std::printf("%6u  %-30s %10zu %10zu %7.3f %9.2f%s\n", unsigned(s.label), s.id.c_str(), reference[s.label],
                grownCount[s.label], dice, depthMm[s.label], thin ? "  thin" : "");
    if (reference[s.label] <= 1000 || dice >= 0.90) continue;
    CAPTURE(s.id);
    CAPTURE(dice);
    CHECK_MESSAGE(thin, "below 0.90 and not thin");
    if (!thin) continue;
    CHECK(dice >= 0.80);
    const double nearSurface = disagreementNearSurface(phantom->labels, editor.labels(), s.label, 1.01 * voxelMm);
    std::printf("        %s: %.1f %% of the disagreement within one voxel of its surface\n", s.id.c_str(), 100 * nearSurface);
    CHECK(nearSurface >= 0.95);
  }
}
