// The CPU engine of the multi-label growth (growth_engine.h): visits of 16³ bricks in the order of
// a shared priority queue (growth_brick_queue.h), by all cores; the state, reset and seeds, the
// visits.
//
// A visit copies its brick and a one-voxel halo into a BrickBox (growth_brick_box.h: distances,
// labels and density bytes, unpacked from the 64-bit keys), sweeps it there — rows along the
// contiguous axis, written for the auto-vectoriser (AVX2 where the CPU has it) — and stores back
// the voxels that decreased. The x sweeps run on a transposed copy of the box (y contiguous), as
// the WDT's CPU backend does for the whole volume.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "growth_brick_box.h"
#include "growth_brick_queue.h"
#include "neighbour_steps.h"
#include "wdt/brick_neighbours.h"
#include "wdt/growth_engine.h"
#include "wdt/huge_pages.h"
#include "wdt/stencil.h"
#include "wdt/step_cost.h"

namespace at {

namespace {

using growth_cpu::BrickBox;
using growth_cpu::BrickQueue;
using growth_cpu::Dist;
using growth_cpu::E;
using growth_cpu::kInf;
using growth_cpu::RelaxBoxFn;
using growth_cpu::RowStamps;
using growth_cpu::S;
using wdt::CostKernel;
using wdt::SweepLengths;

unsigned neighbourMask(int x, int y, int z) { return wdt::brickNeighbourMask(x, y, z, E); }

AT_ALWAYS_INLINE std::uint64_t loadKey(const std::uint64_t* p) { return __atomic_load_n(p, __ATOMIC_RELAXED); }
AT_ALWAYS_INLINE void storeKey(std::uint64_t* p, std::uint64_t v) { __atomic_store_n(p, v, __ATOMIC_RELAXED); }

class CpuGrowthEngine final : public GrowthEngine {
 public:
  explicit CpuGrowthEngine(GrowthProblem problem) : p_(std::move(problem)) {
    const Dims d = p_.grid.dims;
    bricks_[0] = (d.x + E - 1) / E;
    bricks_[1] = (d.y + E - 1) / E;
    bricks_[2] = (d.z + E - 1) / E;
    brickCount_ = std::size_t(bricks_[0]) * bricks_[1] * bricks_[2];
    queue_ = std::make_unique<BrickQueue>(brickCount_);
    settled_.assign(brickCount_, 0);
    if (!p_.blocked.empty()) {
      // A brick whose every voxel is blocked (range limit) is never queued: no step enters or
      // leaves a blocked voxel, so a visit could change nothing; its seeds are written directly.
      allBlocked_.assign(brickCount_, 1);
      for (int z = 0; z < d.z; ++z)
        for (int y = 0; y < d.y; ++y)
          for (int x = 0; x < d.x; ++x)
            if (!p_.blocked[d.index(x, y, z)]) allBlocked_[std::size_t(x / E + bricks_[0] * (y / E + bricks_[1] * (z / E)))] = 0;
    }
    for (int a = 0; a < 3; ++a) spacing_[a] = float(p_.grid.spacingMm[a]);
    for (int a = 0; a < 3; ++a) lengths_[a] = wdt::axisSweepLengths(a, spacing_[0], spacing_[1], spacing_[2]);
    avx2_ = __builtin_cpu_supports("avx2") && !std::getenv("AT_WDT_NO_AVX2");
    relaxBox_ = growth_cpu::relaxBoxFunction(p_.kernel, avx2_);
    const int hw = int(std::max(1u, std::thread::hardware_concurrency()));
    threads_ = hw;
    // AT_WDT_THREADS=N forces N threads (benchmarks, and tests of the multi-threaded schedule).
    if (const char* env = std::getenv("AT_WDT_THREADS")) threads_ = std::clamp(std::atoi(env), 1, 256);
  }

  Status apply(const GrowthChange& change, const WdtControl& control, GrowthStats& stats) override {
    const auto t0 = std::chrono::steady_clock::now();
    const int threads = int(std::min<std::size_t>(std::size_t(threads_), std::max<std::size_t>(1, brickCount_ / 4)));
    stats.backendUsed = WdtBackend::Cpu;
    stats.device = "CPU (" + std::to_string(threads) + (threads == 1 ? " thread)" : " threads)");
    if (keys_.empty()) wdt::resizeOnHugePages(keys_, p_.grid.dims.count());
    std::vector<std::pair<int, Dist>> touched;
    stats.voxelsReset = resetVoxels(change, threads, touched) + resetGrownFrom(change.removedSeeds, touched);
    for (const GrowthSeed& s : change.writeSeeds) {
      storeKey(&keys_[s.index], wdt::packGrowthKey(0, s.label));
      queueBricksHolding(s.index, touched);
    }
    if (change.fromScratch) std::fill(settled_.begin(), settled_.end(), 0);
    for (const auto& [b, key] : touched) settled_[std::size_t(b)] = 0;
    pushVisitable(touched);
    runVisits(threads, control, stats);
    stats.msCompute = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return {};
  }

  bool resetsGrownFromRemovedSeeds() const override { return true; }
  const std::vector<std::uint8_t>* hostDensity() const override { return &p_.density; }

  Status readLabels(LabelMap& out) override {
    out = LabelMap(p_.grid, 0);
    if (keys_.empty()) return {};
    for (std::size_t i = 0; i < keys_.size(); ++i) {
      const std::int32_t l = wdt::growthKeyLabel(keys_[i]);
      out.voxels[i] = l == wdt::kNoLabel ? 0 : std::uint16_t(l);
    }
    return {};
  }

  Status readDistances(FloatVolume& out) override {
    out = FloatVolume(p_.grid, std::numeric_limits<float>::infinity());
    for (std::size_t i = 0; i < keys_.size(); ++i) {
      const Dist dist = wdt::growthKeyDistance(keys_[i]);
      if (dist != kInf) out.voxels[i] = float(dist) / p_.scale;
    }
    return {};
  }

 private:
  int brickOf(std::size_t index) const {
    const Dims d = p_.grid.dims;
    const std::size_t x = index % std::size_t(d.x), y = (index / std::size_t(d.x)) % std::size_t(d.y),
                      z = index / (std::size_t(d.x) * std::size_t(d.y));
    return int(x / E + std::size_t(bricks_[0]) * (y / E + std::size_t(bricks_[1]) * (z / E)));
  }

  // Queues (key 0) the brick of voxel `index` and every neighbour brick whose halo holds it: a seed
  // written on a brick's face must reach the brick across it even when no voxel of its own brick
  // is lowered (a face of seeds and voxels outside the range limit).
  void queueBricksHolding(std::size_t index, std::vector<std::pair<int, Dist>>& touched) const {
    const Dims d = p_.grid.dims;
    const int x = int(index % std::size_t(d.x)), y = int((index / std::size_t(d.x)) % std::size_t(d.y)),
              z = int(index / (std::size_t(d.x) * std::size_t(d.y)));
    const int brick[3] = {x / E, y / E, z / E};
    touched.push_back({brickOf(index), 0});
    const unsigned mask = neighbourMask(x % E, y % E, z % E);
    for (int n = 0; n < 27; ++n) {
      if (!(mask & (1u << n))) continue;
      const int nb[3] = {brick[0] + n % 3 - 1, brick[1] + (n / 3) % 3 - 1, brick[2] + n / 9 - 1};
      if (nb[0] < 0 || nb[1] < 0 || nb[2] < 0 || nb[0] >= bricks_[0] || nb[1] >= bricks_[1] || nb[2] >= bricks_[2]) continue;
      touched.push_back({nb[0] + bricks_[0] * (nb[1] + bricks_[1] * nb[2]), 0});
    }
  }

  // A fresh state, or the reset of the change's labels; the bricks touched go into `touched` with
  // key 0 (they are regrown from their surroundings first).
  std::size_t resetVoxels(const GrowthChange& change, int threads, std::vector<std::pair<int, Dist>>& touched) {
    const Dims d = p_.grid.dims;
    if (!change.fromScratch && change.resetLabels.empty()) return 0;
    std::vector<std::uint8_t> reset(std::size_t(1) << 16, 0);
    for (std::uint16_t l : change.resetLabels) reset[l] = 1;
    const std::uint64_t none = wdt::packGrowthKey(kInf, wdt::kNoLabel);
    std::vector<std::uint8_t> hit(brickCount_, 0);  // written by several threads: the same value
    std::atomic<std::size_t> count{0};
    auto work = [&](int t) {
      std::size_t n = 0;
      for (int z = int(std::int64_t(d.z) * t / threads); z < int(std::int64_t(d.z) * (t + 1) / threads); ++z) {
        std::uint64_t* slice = keys_.data() + std::size_t(d.x) * d.y * std::size_t(z);
        if (change.fromScratch) {
          std::fill(slice, slice + std::size_t(d.x) * d.y, none);
          continue;
        }
        for (int y = 0; y < d.y; ++y)
          for (int x = 0; x < d.x; ++x) {
            std::uint64_t& key = slice[x + std::size_t(d.x) * y];
            const std::int32_t l = wdt::growthKeyLabel(key);
            if (l == wdt::kNoLabel || !reset[std::size_t(l)]) continue;
            key = none;
            ++n;
            __atomic_store_n(&hit[std::size_t(x / E + bricks_[0] * (y / E + bricks_[1] * (z / E)))], 1, __ATOMIC_RELAXED);
          }
      }
      count += n;
    };
    std::vector<std::thread> team;
    for (int t = 1; t < threads; ++t) team.emplace_back(work, t);
    work(0);
    for (std::thread& t : team) t.join();
    for (std::size_t b = 0; b < brickCount_; ++b)
      if (hit[b]) touched.push_back({int(b), 0});
    return count;
  }

  // Resets (+infinity, no label) every voxel whose pair came from a removed seed, found on the old
  // pairs before any is reset: the removed seeds' voxels, then each neighbour v of a found voxel u
  // with u's label and D(v) = D(u) + cost(u → v) (a shortest path through u reaches v; sums are
  // exact, so the test is too). A voxel that another path reaches as cheaply is reset as well and
  // regrown to the same pair. Every voxel not found keeps a pair that a chain of steps from a kept
  // seed still gives, so regrowing the found ones from their surroundings (their bricks are queued)
  // ends at the new seeds' fixed point: an edit costs the region it changes.
  std::size_t resetGrownFrom(const std::vector<GrowthSeed>& removed, std::vector<std::pair<int, Dist>>& touched) {
    if (removed.empty() || keys_.empty()) return 0;
    const Dims d = p_.grid.dims;
    const std::vector<wdt::NeighbourStep> steps = wdt::neighbourSteps(d, spacing_[0], spacing_[1], spacing_[2]);
    std::vector<std::uint8_t> found(d.count(), 0);
    std::vector<std::size_t> list;
    for (const GrowthSeed& s : removed)
      if (!found[s.index]) found[s.index] = 1, list.push_back(s.index);
    wdt::withCostKernel(p_.kernel, [&]<CostKernel K>() {
      for (std::size_t head = 0; head < list.size(); ++head) {
        const std::size_t u = list[head];
        const std::uint64_t ku = keys_[u];
        const Dist du = wdt::growthKeyDistance(ku);
        const std::int32_t lu = wdt::growthKeyLabel(ku);
        if (du == kInf || lu == wdt::kNoLabel) continue;
        const float fu = densityOf(p_, u);
        const int x = int(u % std::size_t(d.x)), y = int(u / std::size_t(d.x) % std::size_t(d.y)),
                  z = int(u / (std::size_t(d.x) * std::size_t(d.y)));
        for (const wdt::NeighbourStep& st : steps) {
          if (!d.contains(x + st.dx, y + st.dy, z + st.dz)) continue;
          const std::size_t v = std::size_t(std::int64_t(u) + st.delta);
          if (found[v]) continue;
          const std::uint64_t kv = keys_[v];
          if (wdt::growthKeyLabel(kv) != lu) continue;
          const std::int32_t cost = wdt::growthStepCost<K>(fu, densityOf(p_, v), st.len, p_.baseCost, p_.scale);
          if (cost == kInf || wdt::addGrowthCost(du, cost) != wdt::growthKeyDistance(kv)) continue;
          found[v] = 1;
          list.push_back(v);
        }
      }
    });
    const std::uint64_t none = wdt::packGrowthKey(kInf, wdt::kNoLabel);
    std::vector<std::uint8_t> hit(brickCount_, 0);
    for (std::size_t v : list) {
      storeKey(&keys_[v], none);
      hit[std::size_t(brickOf(v))] = 1;
    }
    for (std::size_t b = 0; b < brickCount_; ++b)
      if (hit[b]) touched.push_back({int(b), 0});
    return list.size();
  }

  // Queues `items` but the bricks whose every voxel is blocked (allBlocked_).
  void pushVisitable(std::vector<std::pair<int, Dist>>& items) {
    if (!allBlocked_.empty())
      std::erase_if(items, [&](const std::pair<int, Dist>& item) { return allBlocked_[std::size_t(item.first)] != 0; });
    queue_->push(items);
  }

  // Visits until no brick is queued or the run is cancelled (queued bricks then stay queued).
  void runVisits(int threads, const WdtControl& control, GrowthStats& stats) {
    std::atomic<std::size_t> visits{0};
    std::atomic<bool> cancelled{false};
    auto worker = [&] {
      auto box = std::make_unique<BrickBox>();
      auto stamps = std::make_unique<RowStamps>();
      std::vector<std::pair<int, Dist>> queued;
      std::size_t n = 0;
      bool stop = false;
      for (int b; (b = queue_->pop(control.cancel, stop)) >= 0; ++n) {
        queued.clear();
        visit(b, *box, *stamps, queued);
        pushVisitable(queued);
        queue_->finish(b);
      }
      if (stop) cancelled = true;
      visits += n;
    };
    std::vector<std::thread> team;
    for (int t = 1; t < threads; ++t) team.emplace_back(worker);
    worker();
    for (std::thread& t : team) t.join();
    stats.brickVisits += visits;
    stats.cancelled = cancelled;
    stats.converged = queue_->empty() && !cancelled;
  }

  // One visit of brick b: load, relax, store what decreased; the neighbours whose halo holds a
  // decreased voxel (and b itself if its last local pass still changed something) go into `queued`.
  void visit(int b, BrickBox& box, RowStamps& stamps, std::vector<std::pair<int, Dist>>& queued) {
    const Dims d = p_.grid.dims;
    const int brick[3] = {b % bricks_[0], (b / bricks_[0]) % bricks_[1], b / (bricks_[0] * bricks_[1])};
    const int o[3] = {brick[0] * E, brick[1] * E, brick[2] * E};
    box.ext[0] = std::min(E, d.x - o[0]);
    box.ext[1] = std::min(E, d.y - o[1]);
    box.ext[2] = std::min(E, d.z - o[2]);
    load(box, o);
    const bool stillChanging = relaxBox_(box, stamps, settled_[std::size_t(b)] != 0, lengths_, p_.baseCost, p_.scale);
    settled_[std::size_t(b)] = !stillChanging;
    Dist faceMin[27];
    Dist brickMin = kInf;
    store(box, stamps, o, faceMin, brickMin);
    for (int n = 0; n < 27; ++n) {
      if (!(faceMin[n] < kInf)) continue;
      const int nb[3] = {brick[0] + n % 3 - 1, brick[1] + (n / 3) % 3 - 1, brick[2] + n / 9 - 1};
      if (nb[0] < 0 || nb[1] < 0 || nb[2] < 0 || nb[0] >= bricks_[0] || nb[1] >= bricks_[1] || nb[2] >= bricks_[2]) continue;
      queued.push_back({nb[0] + bricks_[0] * (nb[1] + bricks_[1] * nb[2]), faceMin[n]});
    }
    if (stillChanging) queued.push_back({b, brickMin});
  }

  // The brick at voxel origin o and its halo into the box (off-grid cells: +infinity, kNoLabel).
  // The box's rows lie a grid row apart; each is fetched a few rows ahead (without that, half of a
  // visit's time went into waiting for them).
  void load(BrickBox& box, const int o[3]) {
    const Dims d = p_.grid.dims;
    const std::size_t nx = std::size_t(d.x), nxy = nx * std::size_t(d.y);
    const int x0 = std::max(0, o[0] - 1), x1 = std::min(d.x, o[0] + E + 1);  // grid x range of the box
    const auto rowStart = [&](int y, int z) -> std::ptrdiff_t {
      const int gy = o[1] + y - 1, gz = o[2] + z - 1;
      if (gy < 0 || gy >= d.y || gz < 0 || gz >= d.z) return -1;
      return std::ptrdiff_t(nx * std::size_t(gy) + nxy * std::size_t(gz));
    };
    constexpr int kAhead = 4;
    for (int r = 0; r < kAhead; ++r) prefetchRow(rowStart(r % S, r / S), x0, x1);
    for (int z = 0; z < S; ++z)
      for (int y = 0; y < S; ++y) {
        const int ahead = y + S * z + kAhead;
        if (ahead < S * S) prefetchRow(rowStart(ahead % S, ahead / S), x0, x1);
        const int cell = S * (y + S * z);
        const std::ptrdiff_t g = rowStart(y, z);
        const int first = g < 0 ? S : x0 - o[0] + 1, last = g < 0 ? S : x1 - o[0] + 1;  // box x range in the grid
        for (int x = 0; x < S; ++x) {
          if (x >= first && x < last) continue;
          box.d[cell + x] = kInf;
          box.l[cell + x] = wdt::kNoLabel;
          box.f[cell + x] = 0;
        }
        for (int x = first; x < last; ++x) {
          const std::size_t v = std::size_t(g) + std::size_t(x + o[0] - 1);
          const std::uint64_t key = loadKey(&keys_[v]);
          box.d[cell + x] = wdt::growthKeyDistance(key);
          box.l[cell + x] = wdt::growthKeyLabel(key);
          box.f[cell + x] = densityOf(p_, v);
        }
      }
    growth_cpu::transposeBox(box.f, box.fT);
  }

  void prefetchRow(std::ptrdiff_t rowStart, int x0, int x1) const {
    if (rowStart < 0) return;
    const char* k = reinterpret_cast<const char*>(keys_.data() + rowStart + x0);
    for (int b = 0; b < (x1 - x0) * 8; b += 64) __builtin_prefetch(k + b, 0);
    __builtin_prefetch(p_.density.data() + rowStart + x0, 0);
  }

  // Stores the brick's voxels that decreased (those of the lines along x the visit changed, see
  // RowStamps). faceMin[n]: the smallest new distance among them that lies in the halo of
  // neighbour n (bit n of neighbourMask; +infinity if none); brickMin: the smallest of all.
  void store(const BrickBox& box, const RowStamps& stamps, const int o[3], Dist faceMin[27], Dist& brickMin) {
    const Dims d = p_.grid.dims;
    const std::size_t nx = std::size_t(d.x), nxy = nx * std::size_t(d.y);
    std::fill(faceMin, faceMin + 27, kInf);
    for (int z = 0; z < box.ext[2]; ++z)
      for (int y = 0; y < box.ext[1]; ++y) {
        if (stamps.lineX[z + 1][y + 1] <= 1) continue;  // nothing on this line changed
        const std::size_t g = std::size_t(o[0]) + nx * std::size_t(o[1] + y) + nxy * std::size_t(o[2] + z);
        const int cell = 1 + S * (y + 1 + S * (z + 1));
        const bool faceYZ = y == 0 || y == E - 1 || z == 0 || z == E - 1;
        for (int x = 0; x < box.ext[0]; ++x) {
          const Dist dist = box.d[cell + x];
          const std::uint64_t key = wdt::packGrowthKey(dist, box.l[cell + x]);
          // Only this visit writes the brick's voxels, so they still hold what it loaded.
          if (key == loadKey(&keys_[g + std::size_t(x)])) continue;
          storeKey(&keys_[g + std::size_t(x)], key);
          brickMin = std::min(brickMin, dist);
          if (!faceYZ && x != 0 && x != E - 1) continue;
          for (unsigned mask = neighbourMask(x, y, z); mask; mask &= mask - 1) {
            const int n = __builtin_ctz(mask);
            faceMin[n] = std::min(faceMin[n], dist);
          }
        }
      }
  }

  GrowthProblem p_;
  std::vector<std::uint64_t> keys_;  // packGrowthKey per voxel; allocated by the first apply
  int bricks_[3] = {0, 0, 0};
  std::size_t brickCount_ = 0;
  std::unique_ptr<BrickQueue> queue_;  // kept between calls: a cancelled run's bricks stay queued
  std::vector<std::uint8_t> settled_;  // per brick: its interior is settled (see RowStamps)
  std::vector<std::uint8_t> allBlocked_;  // per brick, with a range limit: every voxel blocked (never queued)
  float spacing_[3] = {1, 1, 1};
  SweepLengths lengths_[3]{};
  bool avx2_ = false;
  RelaxBoxFn relaxBox_ = nullptr;
  int threads_ = 1;
};

}  // namespace

std::unique_ptr<GrowthEngine> makeCpuGrowthEngine(GrowthProblem problem) {
  return std::make_unique<CpuGrowthEngine>(std::move(problem));
}

}  // namespace at
