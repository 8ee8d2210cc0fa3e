// prepareWdtProblem: HU → density bytes, seeds, and block aggregation for downsampled fields.
#include <algorithm>
#include <atomic>
#include <string>
#include <vector>

#include "core/parallel_rows.h"
#include "wdt/huge_pages.h"
#include "wdt/problem.h"
#include "wdt/stencil.h"

namespace at {

namespace {

// The full-resolution problem arrays over n voxels; returns whether any seed was set. Restrict
// parameters: byte stores may alias anything, and without them every iteration reloads every
// pointer (3× slower, measured at 256³).
bool densityAndSeeds(const std::int16_t* __restrict hu, const std::uint8_t* __restrict mask,
                     const std::uint8_t* __restrict lut, std::uint8_t* __restrict density,
                     std::uint8_t* __restrict seeds, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) density[i] = lut[std::size_t(hu[i] + 32768)];
  std::uint8_t any = 0;
  for (std::size_t i = 0; i < n; ++i) {
    seeds[i] = mask[i] != 0 ? 1 : 0;
    any |= seeds[i];
  }
  return any != 0;
}

}  // namespace

Geometry downsampledGrid(const Geometry& fine, int f) {
  Geometry g = fine;
  g.dims = {(fine.dims.x + f - 1) / f, (fine.dims.y + f - 1) / f, (fine.dims.z + f - 1) / f};
  for (int a = 0; a < 3; ++a) g.spacingMm[a] = fine.spacingMm[a] * f;
  const double c = 0.5 * (f - 1);
  g.originMm = fine.indexToPatient({c, c, c});
  return g;
}

std::vector<std::uint8_t> densityTable(const WdtParams& params) {
  std::vector<std::uint8_t> lut(65536);
  for (int h = -32768; h <= 32767; ++h) lut[std::size_t(h + 32768)] = wdt::densityByte(float(h), params.huMin, params.huMax);
  return lut;
}

Result<WdtProblem> prepareWdtProblem(const Volume& volume, const Mask& seeds, const WdtParams& params) {
  if (auto ok = validateWdtParams(params); !ok) return tl::unexpected(ok.error());
  const Dims d = volume.dims();
  if (d.count() == 0 || volume.voxels.size() != d.count())
    return fail("WDT: the volume is empty (" + d.toString() + ")");
  if (!(seeds.dims() == d) || seeds.voxels.size() != d.count())
    return fail("WDT: structure mask is " + seeds.dims().toString() + " but the volume is " + d.toString() +
                " (the mask must be on the volume's grid)");
  const auto emptyMask = [] { return fail("WDT: structure mask is empty"); };

  // HU → density byte through a table over the whole int16 range (bit-identical to densityByte,
  // which computes each entry), applied by all cores.
  const std::vector<std::uint8_t> lut = densityTable(params);

  WdtProblem problem;
  problem.params = params;
  const int f = params.downsample;
  if (f == 1) {
    problem.grid = volume.geometry;
    wdt::resizeOnHugePages(problem.density, d.count());
    wdt::resizeOnHugePages(problem.seeds, d.count());
    const std::size_t slice = std::size_t(d.x) * d.y;
    std::atomic<bool> anySeed{false};
    forEachBlockInParallel(d.z, [&](int k0, int k1) {
      const std::size_t i0 = slice * k0, n = slice * (k1 - k0);
      if (densityAndSeeds(volume.voxels.data() + i0, seeds.voxels.data() + i0, lut.data(),
                          problem.density.data() + i0, problem.seeds.data() + i0, n))
        anySeed = true;
    });
    // The empty-mask test rides on the copy: a separate scan costs ~3 ms at 256³.
    if (!anySeed) return emptyMask();
    return problem;
  }

  // Blocks aggregate by the MAXIMUM density: a coarse voxel is as hard to enter as the densest
  // fine voxel in it. A one-voxel bone wall therefore stays a full wall at every factor and a
  // hover field cannot leak through it (the mean would dilute it to 1/f of its weight per block
  // and the field would flow into the neighbouring compartment). The price: thin air channels
  // narrower than a block close up on the coarse grid — an overestimate, never a leak.
  // A coarse voxel is a seed if any fine voxel of its block is.
  if (std::none_of(seeds.voxels.begin(), seeds.voxels.end(), [](std::uint8_t v) { return v != 0; }))
    return emptyMask();
  problem.grid = downsampledGrid(volume.geometry, f);
  const Dims c = problem.grid.dims;
  problem.density.assign(c.count(), 0);
  problem.seeds.assign(c.count(), 0);
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j) {
      const std::size_t fineRow = d.index(0, j, k);
      const std::size_t coarseRow = c.index(0, j / f, k / f);
      for (int i = 0; i < d.x; ++i) {
        const std::uint8_t q = lut[std::size_t(volume.voxels[fineRow + i] + 32768)];
        std::uint8_t& dq = problem.density[coarseRow + i / f];
        dq = std::max(dq, q);
        if (seeds.voxels[fineRow + i]) problem.seeds[coarseRow + i / f] = 1;
      }
    }
  return problem;
}

}  // namespace at
