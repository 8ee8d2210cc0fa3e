// The CPU engine of the multi-label growth (growth_engine.h): visits of 16³ bricks in the order of
// a shared priority queue, by all cores.
//
// [SECTION] Brick box   a brick and its halo in local arrays, and the sweeps over them
// [SECTION] Engine      the state, the queue of bricks, reset and seeds, the visits
//
// A visit copies its brick and a one-voxel halo into a BrickBox (distances, labels and density
// bytes, unpacked from the 64-bit keys), sweeps it there — rows along the contiguous axis, written
// for the auto-vectoriser (AVX2 where the CPU has it) — and stores back the voxels that decreased.
// The x sweeps run on a transposed copy of the box (y contiguous), as the WDT's CPU backend does
// for the whole volume.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <condition_variable>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <queue>
#include <string>
#include <thread>
#include <vector>

#include "wdt/brick_neighbours.h"
#include "wdt/growth_engine.h"
#include "wdt/huge_pages.h"
#include "wdt/stencil.h"
#include "wdt/step_cost.h"
#include "neighbour_steps.h"

namespace at {

namespace {

using wdt::CostKernel;
using wdt::SweepLengths;

constexpr int E = kGrowthBrickEdge;
constexpr int S = E + 2;  // a box edge: the brick and its halo
constexpr int kCells = S * S * S;
constexpr std::int32_t kInf = wdt::kGrowthInf;
using Dist = std::int32_t;  // fixed-point distance (wdt/step_cost.h)

#define AT_ALWAYS_INLINE inline __attribute__((always_inline))

// ─────────────────────────────────────────────────────────────────────────────────────────────
// [SECTION] Brick box
// ─────────────────────────────────────────────────────────────────────────────────────────────

// A brick with its halo: distances d, labels l and densities f (densityFromByte: kept as floats, so
// that the sweeps convert no bytes). Layout N: x fastest, cell x + S·(y + S·z) for box coordinates 0 … S − 1
// (0 and S − 1 are the halo); layout T (the x sweeps): y fastest, cell y + S·(x + S·z). Cells off
// the grid hold (+infinity, kNoLabel) and are never swept.
struct BrickBox {
  alignas(64) Dist d[kCells];
  alignas(64) std::int32_t l[kCells];
  alignas(64) float f[kCells];
  alignas(64) Dist dT[kCells];
  alignas(64) std::int32_t lT[kCells];
  alignas(64) float fT[kCells];
  int ext[3] = {E, E, E};  // voxels of the brick inside the grid, per axis
};

// One row of a plane: voxels 1 … n of `d`, `l` (densities f) from the rows c − 1, c, c + 1 of the
// previous plane; n = FixedN, or rowLength when FixedN is 0. Returns the mask of the voxels that
// changed (bit b for voxel b).
template <CostKernel K, int FixedN>
AT_ALWAYS_INLINE unsigned relaxRow(Dist* __restrict d, std::int32_t* __restrict l, const float* __restrict f,
                                   const Dist* __restrict pm, const Dist* __restrict p0, const Dist* __restrict pp,
                                   const std::int32_t* __restrict lm, const std::int32_t* __restrict l0,
                                   const std::int32_t* __restrict lp, const float* __restrict fm,
                                   const float* __restrict f0, const float* __restrict fp, int rowLength,
                                   SweepLengths len, float base, float scale) {
  const int n = FixedN ? FixedN : rowLength;  // full rows: a fixed count the compiler unrolls
  std::int32_t changed[E + 1];
#pragma GCC ivdep
  for (int b = 1; b <= n; ++b) {
    const Dist nb[3][3] = {{pm[b - 1], pm[b], pm[b + 1]}, {p0[b - 1], p0[b], p0[b + 1]}, {pp[b - 1], pp[b], pp[b + 1]}};
    const std::int32_t nl[3][3] = {
        {lm[b - 1], lm[b], lm[b + 1]}, {l0[b - 1], l0[b], l0[b + 1]}, {lp[b - 1], lp[b], lp[b + 1]}};
    const float fn[3][3] = {{fm[b - 1], fm[b], fm[b + 1]}, {f0[b - 1], f0[b], f0[b + 1]}, {fp[b - 1], fp[b], fp[b + 1]}};
    Dist dv = d[b];
    std::int32_t lv = l[b];
    const Dist dOld = dv;
    const std::int32_t lOld = lv;
    wdt::relaxLabelledVoxel<K>(dv, lv, nb, nl, fn, f[b], len, base, scale);
    changed[b] = (dv ^ dOld) | (lv ^ lOld);
    d[b] = dv;
    l[b] = lv;
  }
  unsigned mask = 0;
  for (int b = 1; b <= n; ++b) mask |= unsigned(changed[b] != 0) << b;
  return mask;
}

// Which rows a sweep must relax. A sweep along axis A relaxes each voxel from its 9 neighbours in
// the previous plane, so a row needs it again only if a voxel of the three previous-plane rows next
// to it decreased since the row was last relaxed in that direction. The sweeps walk two families of
// lines: lines along x (the y and z sweeps' rows, indexed [z][y]) and lines along y (the x sweeps'
// rows in layout T, indexed [z][x]). `lineX`, `lineY` hold the clock time of the last change of any
// voxel of a line, `swept` the time each row was last relaxed, per sweep direction. A visit starts
// with every halo line marked changed, and every interior line too unless the brick's interior is
// known to be settled (its last visit ended with a pass that changed nothing, and no reset or seed
// touched it since). Changes of an x-halo voxel are marked in the lines along y only: every step
// from it moves along x, and the x sweeps cover those steps (likewise for the y halo).
struct RowStamps {
  int lineX[S][S];
  int lineY[S][S];
  int swept[6][S][S];  // [sweep axis · 2 + (direction < 0)][a][c]
  int clock = 1;

  void start(const int ext[3], bool settled) {
    for (int z = 0; z < S; ++z)
      for (int u = 0; u < S; ++u) {
        const bool haloZ = z == 0 || z > ext[2];
        lineX[z][u] = settled && !(haloZ || u == 0 || u > ext[1]) ? 0 : 1;
        lineY[z][u] = settled && !(haloZ || u == 0 || u > ext[0]) ? 0 : 1;
      }
    std::memset(swept, 0, sizeof swept);
    clock = 1;
  }
};

// The box arrays and strides of a sweep along Axis (0 = x in layout T, 1 = y, 2 = z in layout N):
// planes along A, rows along C, voxels along B (contiguous).
template <int Axis>
struct SweepAxis {
  static constexpr int strideA = Axis == 2 ? S * S : S;
  static constexpr int strideC = Axis == 2 ? S : S * S;
  static constexpr int a = Axis, b = Axis == 0 ? 1 : 0, c = Axis == 2 ? 1 : 2;
  // The stamp of the row at plane pa, row pc (its own family), and of the line of the other family
  // through voxel pb of that row.
  static int& own(RowStamps& st, int pa, int pc) {
    return Axis == 1 ? st.lineX[pc][pa] : Axis == 2 ? st.lineX[pa][pc] : st.lineY[pc][pa];
  }
  static int& cross(RowStamps& st, int pa, int pb, int pc) {
    return Axis == 1 ? st.lineY[pc][pb] : Axis == 2 ? st.lineY[pa][pb] : st.lineX[pc][pb];
  }
};

// Whether row (pa, pc) must be relaxed by the sweep of direction dir.
template <int Axis>
AT_ALWAYS_INLINE bool rowDirty(RowStamps& st, const int* swept, int pa, int pc, int dir) {
  using X = SweepAxis<Axis>;
  const int prev = pa - dir;
  const int latest = std::max({X::own(st, prev, pc - 1), X::own(st, prev, pc), X::own(st, prev, pc + 1)});
  return latest > swept[pa * S + pc];
}

template <int Axis>
bool anyRowDirty(RowStamps& st, const int ext[3], int dir) {
  const int* swept = &st.swept[Axis * 2 + (dir < 0)][0][0];
  for (int pa = 1; pa <= ext[SweepAxis<Axis>::a]; ++pa)
    for (int pc = 1; pc <= ext[SweepAxis<Axis>::c]; ++pc)
      if (rowDirty<Axis>(st, swept, pa, pc, dir)) return true;
  return false;
}

// One sweep along Axis in direction dir over the rows that need it. Returns whether anything changed.
template <CostKernel K, int Axis>
AT_ALWAYS_INLINE bool sweepBox(BrickBox& box, RowStamps& st, int dir, SweepLengths len, float base, float scale) {
  using X = SweepAxis<Axis>;
  Dist* d = Axis == 0 ? box.dT : box.d;
  std::int32_t* l = Axis == 0 ? box.lT : box.l;
  const float* f = Axis == 0 ? box.fT : box.f;
  const int extA = box.ext[X::a], extB = box.ext[X::b], extC = box.ext[X::c];
  int* swept = &st.swept[Axis * 2 + (dir < 0)][0][0];
  const int t = ++st.clock;
  bool changed = false;
  for (int step = 0; step < extA; ++step) {
    const int pa = dir > 0 ? 1 + step : extA - step;
    for (int pc = 1; pc <= extC; ++pc) {
      if (!rowDirty<Axis>(st, swept, pa, pc, dir)) continue;
      swept[pa * S + pc] = t;
      const int row = pa * X::strideA + pc * X::strideC;
      const int prev = row - dir * X::strideA;
      constexpr int sc = X::strideC;
      Dist* dr = d + row;
      std::int32_t* lr = l + row;
      const float* fr = f + row;
      const Dist* dp = d + prev;
      const float* fp = f + prev;
      const std::int32_t* lp = l + prev;
      const unsigned mask =
          extB == E ? relaxRow<K, E>(dr, lr, fr, dp - sc, dp, dp + sc, lp - sc, lp, lp + sc, fp - sc, fp, fp + sc, E, len, base, scale)
                    : relaxRow<K, 0>(dr, lr, fr, dp - sc, dp, dp + sc, lp - sc, lp, lp + sc, fp - sc, fp, fp + sc, extB,
                                     len, base, scale);
      if (!mask) continue;
      changed = true;
      X::own(st, pa, pc) = t;
      for (unsigned m = mask; m; m &= m - 1) X::cross(st, pa, __builtin_ctz(m), pc) = t;
    }
  }
  return changed;
}

// t[y + S·(x + S·z)] = s[x + S·(y + S·z)] (the same map takes T back to N).
template <class T>
AT_ALWAYS_INLINE void transposeBox(const T* __restrict s, T* __restrict t) {
  for (int z = 0; z < S; ++z)
    for (int y = 0; y < S; ++y)
      for (int x = 0; x < S; ++x) t[y + S * (x + S * z)] = s[x + S * (y + S * z)];
}

// Local passes of y± and z± (layout N) and x± (layout T, transposed only when an x sweep has rows
// to relax) until a pass changes nothing or kLocalPasses ran; returns whether the last pass still
// changed something. One function per kernel, with an AVX2 clone.
constexpr int kLocalPasses = 16;

template <CostKernel K>
AT_ALWAYS_INLINE bool relaxBoxWith(BrickBox& box, RowStamps& st, bool settled, const SweepLengths len[3], float base,
                                   float scale) {
  st.start(box.ext, settled);
  bool changed = true;
  for (int pass = 0; pass < kLocalPasses && changed; ++pass) {
    changed = false;
    for (int dir : {+1, -1}) changed |= sweepBox<K, 1>(box, st, dir, len[1], base, scale);
    for (int dir : {+1, -1}) changed |= sweepBox<K, 2>(box, st, dir, len[2], base, scale);
    if (anyRowDirty<0>(st, box.ext, +1) || anyRowDirty<0>(st, box.ext, -1)) {
      transposeBox(box.d, box.dT);
      transposeBox(box.l, box.lT);
      bool changedX = false;
      for (int dir : {+1, -1}) changedX |= sweepBox<K, 0>(box, st, dir, len[0], base, scale);
      if (changedX) {
        transposeBox(box.dT, box.d);
        transposeBox(box.lT, box.l);
      }
      changed |= changedX;
    }
  }
  return changed;
}

template <CostKernel K>
bool relaxBoxBaseline(BrickBox& box, RowStamps& st, bool settled, const SweepLengths len[3], float base, float scale) {
  return relaxBoxWith<K>(box, st, settled, len, base, scale);
}

template <CostKernel K>
__attribute__((target("avx2"))) bool relaxBoxAvx2(BrickBox& box, RowStamps& st, bool settled, const SweepLengths len[3],
                                                  float base, float scale) {
  return relaxBoxWith<K>(box, st, settled, len, base, scale);
}

using RelaxBoxFn = bool (*)(BrickBox&, RowStamps&, bool, const SweepLengths[3], float, float);

RelaxBoxFn relaxBoxFunction(CostKernel k, bool avx2) {
  return wdt::withCostKernel(k, [avx2]<CostKernel K>() -> RelaxBoxFn { return avx2 ? &relaxBoxAvx2<K> : &relaxBoxBaseline<K>; });
}

unsigned neighbourMask(int x, int y, int z) { return wdt::brickNeighbourMask(x, y, z, E); }

// ─────────────────────────────────────────────────────────────────────────────────────────────
// [SECTION] Engine
// ─────────────────────────────────────────────────────────────────────────────────────────────

AT_ALWAYS_INLINE std::uint64_t loadKey(const std::uint64_t* p) { return __atomic_load_n(p, __ATOMIC_RELAXED); }
AT_ALWAYS_INLINE void storeKey(std::uint64_t* p, std::uint64_t v) { __atomic_store_n(p, v, __ATOMIC_RELAXED); }

// The bricks waiting for a visit, smallest key first: a brick's key is the smallest distance among
// the changed voxels that queued it, so the front is worked from the seeds outwards (brick-level
// Dijkstra) and a brick is mostly visited once its surroundings have settled. The GPU runs rounds
// over every queued brick instead; on a few cores the order saves visits (measured at 128³:
// 5.3 visits a brick in rounds, bench/RESULTS.md). A brick being visited is not handed out again:
// one queued during its visit is queued again when the visit ends, so it always sees the stores
// that queued it (the mutex orders them). One lock per visit (~0.1 ms of work).
class BrickQueue {
 public:
  explicit BrickQueue(std::size_t bricks) : key_(bricks, kInf), again_(bricks, kInf), running_(bricks, 0) {}

  // Queues the bricks of `items` (brick, key) or lowers their keys.
  void push(const std::vector<std::pair<int, Dist>>& items) {
    if (items.empty()) return;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      for (const auto& [b, key] : items) pushLocked(b, key);
    }
    wake_.notify_all();
  }

  // The next brick to visit, or −1 once nothing is queued and no visit runs, or when *cancel is
  // set (queued bricks then stay queued).
  int pop(const std::atomic<bool>* cancel, bool& cancelled) {
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      if (cancel && cancel->load(std::memory_order_relaxed)) {
        cancelled = !heap_.empty() || running_count_ > 0;
        return -1;
      }
      while (!heap_.empty()) {
        const auto [key, b] = heap_.top();
        heap_.pop();
        if (key != key_[std::size_t(b)]) continue;  // an older entry of a brick whose key went down
        key_[std::size_t(b)] = kInf;
        running_[std::size_t(b)] = 1;
        ++running_count_;
        return b;
      }
      if (running_count_ == 0) return -1;
      wake_.wait(lock);
    }
  }

  // Ends the visit of b (and queues it again if it was queued meanwhile).
  void finish(int b) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      running_[std::size_t(b)] = 0;
      --running_count_;
      if (again_[std::size_t(b)] < kInf) {
        pushLocked(b, again_[std::size_t(b)]);
        again_[std::size_t(b)] = kInf;
      }
    }
    wake_.notify_all();
  }

  bool empty() const { return heap_.empty(); }

 private:
  void pushLocked(int b, Dist key) {
    const std::size_t i = std::size_t(b);
    if (running_[i]) {
      again_[i] = std::min(again_[i], key);
    } else if (key < key_[i]) {
      key_[i] = key;
      heap_.push({key, b});
    }
  }

  std::mutex mutex_;
  std::condition_variable wake_;
  std::priority_queue<std::pair<Dist, int>, std::vector<std::pair<Dist, int>>, std::greater<>> heap_;
  std::vector<Dist> key_;    // kInf when not queued
  std::vector<Dist> again_;  // key to queue with when the running visit ends
  std::vector<char> running_;
  int running_count_ = 0;
};

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
    for (int a = 0; a < 3; ++a) spacing_[a] = float(p_.grid.spacingMm[a]);
    for (int a = 0; a < 3; ++a) lengths_[a] = wdt::axisSweepLengths(a, spacing_[0], spacing_[1], spacing_[2]);
    avx2_ = __builtin_cpu_supports("avx2") && !std::getenv("AT_WDT_NO_AVX2");
    relaxBox_ = relaxBoxFunction(p_.kernel, avx2_);
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
    queue_->push(touched);
    runVisits(threads, control, stats);
    stats.msCompute = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    return {};
  }

  bool resetsGrownFromRemovedSeeds() const override { return true; }

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
        queue_->push(queued);
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
    transposeBox(box.f, box.fT);
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
