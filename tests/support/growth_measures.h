// The measures of grow-from-seeds at its default settings (segment/growth_settings.h), shared by
// the tests and bench/: a µCT-like volume the tests make, and seeds chosen from reference labels by
// one documented rule (never tuned per structure).
//
// µCT-like volume: the phantom's voxels, re-spaced to `voxelMm` (a small animal's temporal bone)
// and written as uint8 plain intensities (−1000 … 2000 HU → 0 … 255) with extra Gaussian noise —
// no HU, no modality, as a µCT export arrives. Its intensity model is what the loader decides for
// unsigned data without rescale (plain, histogram window).
//
// Seed rule ("deepest interior points"): in a region, the voxel farthest from the region's outside
// (in mm), then greedily the next deepest voxels at least `apartFraction` of the region's box
// diagonal from those taken, up to `count`. Each seed is one voxel, as a single click.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <vector>

#include "segment/distance_map.h"
#include "volume/intensity.h"
#include "volume/phantom.h"
#include "volume/structure.h"
#include "wdt/label_growth.h"

namespace at::test {

struct MicroCt {
  Dataset dataset;     // uint8 plain intensities; labels: the phantom's, re-spaced
  Mask bone;           // voxels of bone intensity: at or above the midpoint of soft tissue and
                       // cancellous bone (320 HU before conversion)
  Mask air;            // voxels below the midpoint of air and soft tissue (−480 HU)
  std::uint64_t seed = 0;
};

inline MicroCt makeMicroCt(int size, double voxelMm, double noiseSigma, std::uint64_t seed) {
  PhantomOptions options;
  options.size = size;
  options.extentMm = 51.2;
  MicroCt out;
  out.seed = seed;
  out.dataset = makePhantom(options);
  Dataset& ds = out.dataset;
  Geometry g = ds.volume.geometry;
  const double scale = voxelMm / g.spacingMm[0];
  for (int a = 0; a < 3; ++a) g.spacingMm[std::size_t(a)] = voxelMm, g.originMm[std::size_t(a)] *= scale;
  ds.volume.geometry = g;
  ds.labels.geometry = g;
  out.bone = Mask(g, 0);
  out.air = Mask(g, 0);
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0.0, noiseSigma);
  for (std::size_t v = 0; v < ds.volume.voxels.size(); ++v) {
    const double hu = ds.volume.voxels[v];
    out.bone.voxels[v] = hu >= 320.0;
    out.air.voxels[v] = hu < -480.0;
    const double value = (hu + 1000.0) * 255.0 / 3000.0 + noise(random);
    ds.volume.voxels[v] = std::int16_t(std::clamp(std::lround(value), 0L, 255L));
  }
  ds.id = "microct";
  ds.intensity = IntensityModel{};
  ds.intensity.unit = IntensityUnit::Plain;
  ds.intensity.window = histogramWindow(ds.volume.voxels);
  ds.intensity.reason = "unsigned integer data without rescale (µCT or MR export): plain intensities";
  return out;
}

// The deepest interior points of `region` (non-zero voxels), by the rule above, as seeds of `label`.
inline std::vector<GrowthSeed> deepestSeeds(const Mask& region, int count, double apartFraction, std::uint16_t label) {
  Mask outside(region.geometry, 0);
  for (std::size_t v = 0; v < region.voxels.size(); ++v) outside.voxels[v] = !region.voxels[v];
  const FloatVolume depth = segment::distanceToMask(outside);
  std::vector<std::size_t> order;
  for (std::size_t v = 0; v < region.voxels.size(); ++v)
    if (region.voxels[v]) order.push_back(v);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return depth.voxels[a] > depth.voxels[b]; });
  const Geometry& g = region.geometry;
  const Dims d = g.dims;
  const auto centre = [&](std::size_t v) {
    return g.indexToPatient({double(v % std::size_t(d.x)), double(v / std::size_t(d.x) % std::size_t(d.y)),
                             double(v / (std::size_t(d.x) * std::size_t(d.y)))});
  };
  Vec3 lo{1e30, 1e30, 1e30}, hi{-1e30, -1e30, -1e30};
  for (std::size_t v : order) {
    const Vec3 p = centre(v);
    for (std::size_t a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a]), hi[a] = std::max(hi[a], p[a]);
  }
  const double minApartMm = order.empty() ? 0.0 : apartFraction * norm(hi - lo);
  std::vector<GrowthSeed> seeds;
  std::vector<Vec3> taken;
  for (std::size_t v : order) {
    if (int(seeds.size()) >= count) break;
    const Vec3 p = centre(v);
    if (std::all_of(taken.begin(), taken.end(), [&](const Vec3& q) { return norm(p - q) >= minApartMm; })) {
      taken.push_back(p);
      seeds.push_back({v, label});
    }
  }
  return seeds;
}

// One seed per cell of a lattice of `cellMm`: the deepest voxel of `region` in the cell (a user's
// background dabs spread over a tissue), where it lies at least one voxel inside the region.
inline std::vector<GrowthSeed> latticeSeeds(const Mask& region, double cellMm, std::uint16_t label) {
  Mask outside(region.geometry, 0);
  for (std::size_t v = 0; v < region.voxels.size(); ++v) outside.voxels[v] = !region.voxels[v];
  const FloatVolume depth = segment::distanceToMask(outside);
  const Geometry& g = region.geometry;
  const Dims d = g.dims;
  int cell[3];
  for (std::size_t a = 0; a < 3; ++a) cell[a] = std::max(1, int(std::lround(cellMm / g.spacingMm[a])));
  const double voxel = std::max({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]});
  std::map<std::size_t, std::pair<float, std::size_t>> best;
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const std::size_t v = d.index(i, j, k);
        if (!region.voxels[v] || depth.voxels[v] < 1.5 * voxel) continue;
        const std::size_t c = std::size_t(i / cell[0]) + 1000 * (std::size_t(j / cell[1]) + 1000 * std::size_t(k / cell[2]));
        auto [it, fresh] = best.emplace(c, std::make_pair(depth.voxels[v], v));
        if (!fresh && depth.voxels[v] > it->second.first) it->second = {depth.voxels[v], v};
      }
  std::vector<GrowthSeed> seeds;
  for (const auto& [c, pick] : best) seeds.push_back({pick.second, label});
  return seeds;
}

// The voxels of `labels` equal to `value`.
inline Mask labelRegion(const LabelMap& labels, std::uint16_t value) {
  Mask m(labels.geometry, 0);
  for (std::size_t v = 0; v < labels.voxels.size(); ++v) m.voxels[v] = labels.voxels[v] == value;
  return m;
}

inline double dice(const LabelMap& a, std::uint16_t la, const LabelMap& b, std::uint16_t lb) {
  std::size_t inA = 0, inB = 0, both = 0;
  for (std::size_t v = 0; v < a.voxels.size(); ++v) {
    const bool x = a.voxels[v] == la, y = b.voxels[v] == lb;
    inA += x, inB += y, both += x && y;
  }
  return inA + inB == 0 ? 1.0 : 2.0 * double(both) / double(inA + inB);
}

}  // namespace at::test
