// Seed strokes drawn inside labelled structures the way a user draws them, for accuracy tests on
// datasets whose labels may change (the phantom is redesigned from time to time): the strokes are
// made from whatever labels the dataset has, by a fixed rule, and are a tiny fraction of its
// voxels — never the labels themselves.
//
// Rule, per structure: the voxels deepest inside it (largest distance to its outside, in mm) are
// taken greedily, each at least `spacingFraction` of the structure's extent from those taken
// before (at most `perStructure`), plus the deepest voxel of every other connected part of it
// (a user clicks each air cell); consecutive ones are joined into one stroke where the straight
// line between them stays inside the structure, and are dots otherwise. Background, as a user
// outlines a structure: dots in the unlabelled voxels `ringVoxels` voxels from the structure, one
// every `ringSpacingMm`; and in every cell of a lattice of `backgroundCellMm`, the background voxel
// farthest from every structure, if at least `backgroundClearanceMm` away.
#pragma once

#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "segment/distance_map.h"
#include "segment/seeds.h"
#include "volume/structure.h"

namespace at::test {

struct StrokeRule {
  int perStructure = 8;
  double spacingFraction = 0.15;
  double ringVoxels = 2.0;
  double ringSpacingMm = 0.5;
  double backgroundCellMm = 6.0;
  double backgroundClearanceMm = 0.6;
  double innerRingSpacingMm = 0.5;  // > 0: also dots inside the structure, ringVoxels deep, this far apart
};

// `maxDepthMm` (optional) receives each structure's largest distance from its outside: its half
// thickness (a tube's radius).
inline segment::SeedSet strokesInsideLabels(const Dataset& dataset, const StrokeRule& rule = {},
                                            std::map<std::uint16_t, double>* maxDepthMm = nullptr) {
  const Geometry& g = dataset.labels.geometry;
  const Dims d = g.dims;
  segment::SeedSet set;
  segment::SeedLabel background;
  background.name = "background";
  set.labels.push_back(background);
  for (const Structure& s : dataset.structures) {
    segment::SeedLabel label;
    label.value = s.label;
    label.name = s.id;
    set.labels.push_back(label);
    // The structure's box with a margin for the ring, and the distance inside it to its outside.
    const int margin = int(std::ceil(rule.ringVoxels)) + 2;
    int lo[3] = {d.x, d.y, d.z}, hi[3] = {-1, -1, -1};
    for (int k = 0; k < d.z; ++k)
      for (int j = 0; j < d.y; ++j)
        for (int i = 0; i < d.x; ++i)
          if (dataset.labels.voxels[d.index(i, j, k)] == s.label) {
            const int p[3] = {i, j, k};
            for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], p[a] - margin), hi[a] = std::max(hi[a], p[a] + margin);
          }
    if (hi[0] < 0) continue;
    Geometry box = g;
    box.dims = {hi[0] - lo[0] + 1, hi[1] - lo[1] + 1, hi[2] - lo[2] + 1};
    box.originMm = g.indexToPatient({double(lo[0]), double(lo[1]), double(lo[2])});
    Mask outside(box, 1);
    for (int k = 0; k < box.dims.z; ++k)
      for (int j = 0; j < box.dims.y; ++j)
        for (int i = 0; i < box.dims.x; ++i) {
          const int gi = i + lo[0], gj = j + lo[1], gk = k + lo[2];
          if (d.contains(gi, gj, gk) && dataset.labels.voxels[d.index(gi, gj, gk)] == s.label)
            outside.at(i, j, k) = 0;
        }
    const FloatVolume depth = segment::distanceToMask(outside);
    std::vector<std::pair<float, std::size_t>> order;
    for (std::size_t v = 0; v < depth.voxels.size(); ++v)
      if (!outside.voxels[v]) order.push_back({depth.voxels[v], v});
    std::sort(order.begin(), order.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
    if (maxDepthMm && !order.empty()) (*maxDepthMm)[s.label] = order.front().first;
    const double extent = norm(box.extentMm());
    std::vector<Vec3> picked;
    for (const auto& [dist, v] : order) {
      if (int(picked.size()) >= rule.perStructure) break;
      const Vec3 p = box.indexToPatient({double(v % std::size_t(box.dims.x)),
                                         double(v / std::size_t(box.dims.x) % std::size_t(box.dims.y)),
                                         double(v / (std::size_t(box.dims.x) * box.dims.y))});
      if (std::all_of(picked.begin(), picked.end(), [&](const Vec3& q) { return norm(p - q) >= rule.spacingFraction * extent; })) {
        picked.push_back(p);
      }
    }
    // The deepest voxel of every connected part without a pick (6-connected, 8 voxels or more).
    {
      std::vector<int> part(depth.voxels.size(), -1);
      const Dims bd = box.dims;
      int parts = 0;
      for (const auto& [dist, v] : order) {
        if (part[v] >= 0) continue;
        std::vector<std::size_t> stack{v}, members;
        part[v] = parts;
        while (!stack.empty()) {
          const std::size_t u = stack.back();
          stack.pop_back();
          members.push_back(u);
          const int x = int(u % std::size_t(bd.x)), y = int(u / std::size_t(bd.x) % std::size_t(bd.y)),
                    z = int(u / (std::size_t(bd.x) * bd.y));
          const int n[6][3] = {{x - 1, y, z}, {x + 1, y, z}, {x, y - 1, z}, {x, y + 1, z}, {x, y, z - 1}, {x, y, z + 1}};
          for (const auto& w : n)
            if (bd.contains(w[0], w[1], w[2])) {
              const std::size_t q = bd.index(w[0], w[1], w[2]);
              if (!outside.voxels[q] && part[q] < 0) part[q] = parts, stack.push_back(q);
            }
        }
        ++parts;
        if (members.size() < 8) continue;
        const Vec3 p = box.indexToPatient({double(v % std::size_t(bd.x)), double(v / std::size_t(bd.x) % std::size_t(bd.y)),
                                           double(v / (std::size_t(bd.x) * bd.y))});
        const bool has = std::any_of(picked.begin(), picked.end(), [&](const Vec3& q) {
          const Vec3 ijk = box.patientToIndex(q);
          return part[bd.index(int(std::lround(ijk[0])), int(std::lround(ijk[1])), int(std::lround(ijk[2])))] == part[v];
        });
        if (!has) picked.push_back(p);
      }
    }
    // Dots just inside its surface, where a user outlines a boundary the intensities do not show.
    if (rule.innerRingSpacingMm > 0) {
      const double unit = std::min({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]});
      std::vector<Vec3> ring;
      for (std::size_t v = 0; v < depth.voxels.size(); ++v) {
        const double r = depth.voxels[v] / unit;
        if (outside.voxels[v] || r < rule.ringVoxels - 0.5 || r > rule.ringVoxels + 0.5) continue;
        const Vec3 p = box.indexToPatient({double(v % std::size_t(box.dims.x)),
                                           double(v / std::size_t(box.dims.x) % std::size_t(box.dims.y)),
                                           double(v / (std::size_t(box.dims.x) * box.dims.y))});
        if (std::all_of(ring.begin(), ring.end(), [&](const Vec3& q) { return norm(p - q) >= rule.innerRingSpacingMm; }))
          ring.push_back(p);
      }
      for (const Vec3& p : ring) {
        segment::SeedStroke dot;
        dot.label = set.labels.size() - 1;
        dot.pointsMm.push_back(p);
        set.strokes.push_back(dot);
      }
    }
    // The ring of background dots around it.
    {
      Mask self(box, 0);
      for (std::size_t v = 0; v < self.voxels.size(); ++v) self.voxels[v] = !outside.voxels[v];
      const FloatVolume toSelf = segment::distanceToMask(self);
      const double unit = std::min({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]});
      std::vector<Vec3> ring;
      for (std::size_t v = 0; v < toSelf.voxels.size(); ++v) {
        const double r = toSelf.voxels[v] / unit;
        if (r < rule.ringVoxels - 0.5 || r > rule.ringVoxels + 0.5) continue;
        const Vec3 p = box.indexToPatient({double(v % std::size_t(box.dims.x)),
                                           double(v / std::size_t(box.dims.x) % std::size_t(box.dims.y)),
                                           double(v / (std::size_t(box.dims.x) * box.dims.y))});
        const Vec3 ijk = g.patientToIndex(p);
        const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
        if (!d.contains(i, j, k) || dataset.labels.voxels[d.index(i, j, k)] != 0) continue;
        if (std::all_of(ring.begin(), ring.end(), [&](const Vec3& q) { return norm(p - q) >= rule.ringSpacingMm; }))
          ring.push_back(p);
      }
      for (const Vec3& p : ring) {
        segment::SeedStroke dot;
        dot.label = 0;
        dot.pointsMm.push_back(p);
        set.strokes.push_back(dot);
      }
    }
    const auto inside = [&](const Vec3& p) {
      const Vec3 ijk = g.patientToIndex(p);
      const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
      return d.contains(i, j, k) && dataset.labels.voxels[d.index(i, j, k)] == s.label;
    };
    segment::SeedStroke stroke;
    stroke.label = set.labels.size() - 1;
    const auto finish = [&] {
      set.strokes.push_back(stroke);
      stroke.pointsMm.clear();
    };
    for (const Vec3& p : picked) {
      bool joins = !stroke.pointsMm.empty();
      if (joins)
        for (int t = 1; t < 32 && joins; ++t) joins = inside(stroke.pointsMm.back() + (t / 32.0) * (p - stroke.pointsMm.back()));
      if (!joins && !stroke.pointsMm.empty()) finish();
      stroke.pointsMm.push_back(p);
    }
    if (!stroke.pointsMm.empty()) finish();
  }
  // Background dots: the clearest background voxel of every lattice cell.
  Mask labelled(g, 0);
  for (std::size_t v = 0; v < labelled.voxels.size(); ++v) labelled.voxels[v] = dataset.labels.voxels[v] != 0;
  const FloatVolume clearance = segment::distanceToMask(labelled);
  int cell[3];
  for (int a = 0; a < 3; ++a) cell[a] = std::max(1, int(std::lround(rule.backgroundCellMm / g.spacingMm[std::size_t(a)])));
  std::map<std::size_t, std::pair<float, std::size_t>> best;  // lattice cell → (clearance, voxel)
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const std::size_t v = d.index(i, j, k);
        const float c = clearance.voxels[v];
        if (labelled.voxels[v] || !(c >= rule.backgroundClearanceMm)) continue;
        const std::size_t key = std::size_t(i / cell[0]) + 4096 * (std::size_t(j / cell[1]) + 4096 * std::size_t(k / cell[2]));
        auto& b = best[key];
        if (c > b.first) b = {c, v};
      }
  for (const auto& [key, entry] : best) {
    segment::SeedStroke dot;
    dot.label = 0;
    const std::size_t v = entry.second;
    dot.pointsMm.push_back(g.indexToPatient({double(v % std::size_t(d.x)), double(v / std::size_t(d.x) % std::size_t(d.y)),
                                             double(v / (std::size_t(d.x) * d.y))}));
    set.strokes.push_back(dot);
  }
  return set;
}

}  // namespace at::test
