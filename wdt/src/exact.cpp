// The exact reference (Dijkstra on the 26-connected grid), field upsampling and accuracy.
//
// Candidates are D(a) + stepCost(a → b) with the lengths of wdt::axisSweepLengths and the costs of
// wdt/step_cost.h: the very floats the sweeps add (the sweeps' grouped min-then-add equals add-then-min
// because float addition is monotone). Converged sweeps therefore equal this reference bit for bit.
//
// Queue: Dial's buckets of width W = ½ · (smallest possible step cost). Every step costs at least
// 2W, so a voxel popped from bucket k can only push into buckets > k: all voxels of a bucket are
// final when it is reached, whatever their order inside it, and the result is exact Dijkstra.
// Live keys span at most (largest step cost)/W buckets, so the buckets form a ring. When the base
// cost is 0 (free steps) a binary heap with lazy deletion is used instead.
#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <queue>
#include <vector>

#include "field_sampling.h"
#include "wdt/step_cost.h"
#include "wdt/problem.h"
#include "wdt/stencil.h"

namespace at {

namespace {

using wdt::CostKernel;

constexpr float kInf = std::numeric_limits<float>::infinity();

struct Offset {
  int dx, dy, dz;
  std::int64_t delta;
  float len;
};

// The 26 steps and their lengths (wdt::stepLength: the float every sweep that takes a step uses).
std::vector<Offset> offsets(const Geometry& g) {
  const float sx = float(g.spacingMm[0]), sy = float(g.spacingMm[1]), sz = float(g.spacingMm[2]);
  const Dims d = g.dims;
  std::vector<Offset> out;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy && !dz) continue;
        const std::int64_t delta = dx + std::int64_t(d.x) * (dy + std::int64_t(d.y) * dz);
        out.push_back({dx, dy, dz, delta, wdt::stepLength(dx, dy, dz, sx, sy, sz)});
      }
  return out;
}

// Asks the caches for the 3×3 rows of distances and densities around voxel v (each row holds v's
// x−1, x, x+1 neighbours of one (y, z)). A popped voxel reads and writes those 26 neighbours; the
// voxels of one bucket lie scattered on the front, so without this each pop waits on ~18 misses
// (256³ exact reference 6.7 s → 3.5 s on the 2-core dev machine).
void prefetchNeighbourhood(std::uint32_t v, Dims d, const float* dist, const std::uint8_t* q) {
  const std::int64_t nx = d.x, nxy = std::int64_t(d.x) * d.y;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy) {
      // Integer addresses: rows of border voxels may fall outside the arrays, which a prefetch
      // (a hint, never a fault) tolerates but pointer arithmetic would not.
      const std::int64_t r = std::int64_t(v) + dy * nx + dz * nxy;
      __builtin_prefetch(reinterpret_cast<const void*>(std::uintptr_t(dist) + std::uintptr_t(r * std::int64_t(sizeof(float)))), 1);
      __builtin_prefetch(reinterpret_cast<const void*>(std::uintptr_t(q) + std::uintptr_t(r)), 0);
    }
}

// Dijkstra over `problem` with pop order given by Queue (buckets or heap). Queue::peekAhead names
// a voxel popped soon (or returns false), whose neighbourhood is prefetched.
template <CostKernel K, class Queue>
void dijkstra(const WdtProblem& problem, Queue& queue, std::vector<float>& dist) {
  const Dims d = problem.grid.dims;
  const std::vector<Offset> steps = offsets(problem.grid);
  const std::uint8_t* q = problem.density.data();
  const float base = problem.params.baseCost;
  for (std::size_t i = 0; i < d.count(); ++i)
    if (problem.seeds[i]) {
      dist[i] = 0.0f;
      queue.push(std::uint32_t(i), 0.0f);
    }
  std::uint32_t u;
  float key;
  while (queue.pop(u, key)) {
    std::uint32_t ahead;
    if (queue.peekAhead(ahead)) prefetchNeighbourhood(ahead, d, dist.data(), q);
    // Stale entry: u was improved after this push (and is or will be popped with its lower key).
    // Keys are pushed only on a strict improvement, so the entry holding dist[u] is unique.
    const float du = dist[u];
    if (key != du) continue;
    const std::uint8_t qu = q[u];
    const int x = int(u % std::uint32_t(d.x));
    const std::uint32_t yz = u / std::uint32_t(d.x);
    const int y = int(yz % std::uint32_t(d.y)), z = int(yz / std::uint32_t(d.y));
    const bool interior = x > 0 && y > 0 && z > 0 && x + 1 < d.x && y + 1 < d.y && z + 1 < d.z;
    for (const Offset& s : steps) {
      if (!interior && !d.contains(x + s.dx, y + s.dy, z + s.dz)) continue;
      // A finalised v has dist[v] <= du <= c, so the comparison below rejects it.
      const std::uint32_t v = std::uint32_t(std::int64_t(u) + s.delta);
      const float c = du + wdt::stepCost<K>(qu, q[v], s.len, base);
      if (c < dist[v]) {
        dist[v] = c;
        queue.push(v, c);
      }
    }
  }
}

class BucketQueue {
 public:
  BucketQueue(float width, std::size_t ring) : inv_(1.0 / double(width)), ring_(ring) {}
  void push(std::uint32_t v, float key) {
    std::size_t k = std::size_t(double(key) * inv_);
    if (k < current_) k = current_;  // cannot happen with steps >= 2 widths; kept for safety
    ring_[k % ring_.size()].push_back({v, key});
    ++pending_;
  }
  // The entry kAhead pops ahead in the current bucket, if there is one (stale or not).
  bool peekAhead(std::uint32_t& v) const {
    const std::vector<Entry>& b = ring_[current_ % ring_.size()];
    if (cursor_ + kAhead >= b.size()) return false;
    v = b[cursor_ + kAhead].node;
    return true;
  }
  bool pop(std::uint32_t& v, float& key) {
    if (pending_ == 0) return false;
    for (;;) {
      std::vector<Entry>& b = ring_[current_ % ring_.size()];
      if (cursor_ < b.size()) {
        v = b[cursor_].node;
        key = b[cursor_].key;
        ++cursor_;
        --pending_;
        return true;
      }
      b.clear();
      cursor_ = 0;
      ++current_;
    }
  }

 private:
  struct Entry {
    std::uint32_t node;
    float key;
  };
  static constexpr std::size_t kAhead = 8;
  double inv_;
  std::vector<std::vector<Entry>> ring_;
  std::size_t current_ = 0, cursor_ = 0, pending_ = 0;
};

class HeapQueue {
 public:
  void push(std::uint32_t v, float key) { heap_.push({key, v}); }
  bool peekAhead(std::uint32_t&) const { return false; }
  bool pop(std::uint32_t& v, float& key) {
    if (heap_.empty()) return false;
    key = heap_.top().first;
    v = heap_.top().second;
    heap_.pop();
    return true;
  }

 private:
  using Entry = std::pair<float, std::uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap_;
};

template <CostKernel K>
void exactWith(const WdtProblem& problem, std::vector<float>& dist) {
  const Geometry& g = problem.grid;
  float lenLo = kInf, lenHi = 0;
  for (const Offset& s : offsets(g)) {
    lenLo = std::min(lenLo, s.len);
    lenHi = std::max(lenHi, s.len);
  }
  float wLo, wHi;
  wdt::weightRange(K, problem.params.baseCost, lenLo, wLo, wHi);
  // Smallest cost a step can have, with margin for the rounding of the cost itself.
  const double minCost = double(wLo) * double(lenLo) * (1.0 - 1e-5);
  const double maxCost = double(wHi) * double(lenHi) * (1.0 + 1e-5);
  const double width = 0.5 * minCost;
  const double ring = width > 0 ? std::ceil(maxCost / width) + 2 : 0;
  if (width > 0 && ring < double(1 << 22)) {
    BucketQueue queue{float(width), std::size_t(ring)};
    dijkstra<K>(problem, queue, dist);
  } else {
    HeapQueue queue;
    dijkstra<K>(problem, queue, dist);
  }
}

}  // namespace

Result<FloatVolume> exactWdtOnProblem(const WdtProblem& problem) {
  const Dims d = problem.grid.dims;
  if (d.count() == 0 || problem.density.size() != d.count() || problem.seeds.size() != d.count())
    return fail("WDT exact: problem arrays do not match the grid " + d.toString());
  if (d.count() >= (std::size_t(1) << 32)) return fail("WDT exact: grid " + d.toString() + " is too large");
  FloatVolume out(problem.grid, kInf);
  wdt::withCostKernel(wdt::costKernel(problem.params), [&]<CostKernel K>() { exactWith<K>(problem, out.voxels); });
  return out;
}

Result<FloatVolume> exactWdt(const Volume& volume, const Mask& seeds, const WdtParams& params) {
  WdtParams full = params;
  full.downsample = 1;
  auto problem = prepareWdtProblem(volume, seeds, full);
  if (!problem) return tl::unexpected(problem.error());
  return exactWdtOnProblem(*problem);
}

// Trilinear in the patient frame: each target voxel centre is mapped into the field's index space
// (clamped to the field's extent, so the border blocks hold their value). Where all 8 corners are
// finite the result is the trilinear blend; where any corner is +infinity (the edge of the
// reachable region) blending would give +infinity or a meaningless mix, so the sample takes the
// value of its nearest corner instead (finite or +infinity).
FloatVolume upsampleField(const DistanceField& field, const Geometry& target) {
  const FloatVolume& src = field.distances;
  FloatVolume out(target, kInf);
  if (src.geometry.dims.count() == 0) return out;
  const wdt::detail::GridMap map(src.geometry, target);
  const Dims td = target.dims;
  for (int k = 0; k < td.z; ++k)
    for (int j = 0; j < td.y; ++j)
      for (int i = 0; i < td.x; ++i) out.voxels[td.index(i, j, k)] = wdt::detail::sampleMapped(src, map, i, j, k);
  return out;
}

WdtAccuracy compareToExact(const FloatVolume& field, const FloatVolume& exact) {
  assert(field.voxels.size() == exact.voxels.size() && "compareToExact: fields on different grids");
  WdtAccuracy acc;
  std::vector<double> errs;
  errs.reserve(exact.voxels.size());
  double sum = 0;
  std::size_t within = 0;
  for (std::size_t i = 0; i < exact.voxels.size(); ++i) {
    const double e = exact.voxels[i];
    if (!std::isfinite(e) || !(e > 0)) continue;
    const double v = field.voxels[i];
    const double rel = std::isfinite(v) ? std::abs(v - e) / e : std::numeric_limits<double>::infinity();
    errs.push_back(rel);
    sum += rel;
    if (rel <= 1e-5) ++within;
    if (v < e * (1 - 1e-5)) ++acc.belowExact;
    acc.maxRelErr = std::max(acc.maxRelErr, rel);
  }
  acc.compared = errs.size();
  if (errs.empty()) return acc;
  acc.meanRelErr = sum / double(errs.size());
  acc.exactFraction = double(within) / double(errs.size());
  const std::size_t k = std::min(errs.size() - 1, std::size_t(std::ceil(0.99 * double(errs.size()))) - 1);
  std::nth_element(errs.begin(), errs.begin() + std::ptrdiff_t(k), errs.end());
  acc.p99RelErr = errs[k];
  return acc;
}

}  // namespace at
