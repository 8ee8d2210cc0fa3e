// The CPU backend: the paper's multi-axis sweeps (Algorithm 2), multi-threaded and vectorised.
//
// [SECTION] Row kernel   one row of a plane, vectorised along the contiguous axis (AVX2 or SSE2)
// [SECTION] Team         a spin barrier and the per-plane split of rows among threads
// [SECTION] Schedule     one pass = x+ x− y+ y− z+ z−, transposes, convergence, cancellation
//
// Layout: D is kept with i (x) contiguous ("L1"). The y and z sweeps then have planes that
// contain whole x rows: each thread takes a share of the plane's rows, each row is one vectorised
// loop over x, and the threads meet at a barrier after every plane (the next plane reads this one).
// The x sweeps run across the contiguous axis; instead of strided or gathered access, D is
// transposed per z slice into an "L2" copy with j (y) contiguous, where the x sweeps are again
// sweeps of whole rows (rows along y), and transposed back. The density bytes are transposed once
// per run. Measured on 2 cores at 256³ the two transposes cost less than one sweep each.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <type_traits>
#include <immintrin.h>
#include <vector>

#include "wdt/huge_pages.h"
#include "step_cost.h"
#include "wdt/problem.h"
#include "wdt/stencil.h"

namespace at {

namespace {

using wdt::CostKernel;
using wdt::SweepLengths;

constexpr float kInf = std::numeric_limits<float>::infinity();

#define AT_ALWAYS_INLINE inline __attribute__((always_inline))

// ─────────────────────────────────────────────────────────────────────────────────────────────
// [SECTION] Row kernel
// ─────────────────────────────────────────────────────────────────────────────────────────────

// One row of the current plane and the three rows of the previous plane it reads (c − 1, c, c + 1
// across rows; a missing row is a row of +infinity). `q*` are the density bytes of the same rows.
struct RowArgs {
  float* cur;
  const float* pm;
  const float* p0;
  const float* pp;
  const std::uint8_t* qc;
  const std::uint8_t* qm;
  const std::uint8_t* q0;
  const std::uint8_t* qp;
  int n;
  SweepLengths l;
  float base;
};

// Update of one voxel from its 9 neighbours nb[dc][db] (db along the row, dc across rows).
template <CostKernel K>
AT_ALWAYS_INLINE float relaxVoxel(float cur, const float nb[3][3], const std::uint8_t qn[3][3], std::uint8_t qb,
                                  SweepLengths l, float base) {
  if constexpr (K == CostKernel::EnterDensity) {
    return wdt::enteringUpdate(cur, nb, wdt::densityWeight(qb, base), l);
  } else if constexpr (K == CostKernel::EnterUniform) {
    return wdt::enteringUpdate(cur, nb, 1.0f, l);
  } else {
    const float lens[3][3] = {{l.diagonal, l.alongC, l.diagonal},
                              {l.alongB, l.straight, l.alongB},
                              {l.diagonal, l.alongC, l.diagonal}};
    float best = cur;
    for (int dc = 0; dc < 3; ++dc)
      for (int db = 0; db < 3; ++db)
        best = wdt::minf(best, nb[dc][db] + wdt::stepCost<K>(qn[dc][db], qb, lens[dc][db], base));
    return best;
  }
}

// Edge voxel of a row (i = 0 or n − 1): neighbours beyond the row's ends are +infinity.
template <CostKernel K>
AT_ALWAYS_INLINE int relaxEdge(const RowArgs& a, int i) {
  const float* rows[3] = {a.pm, a.p0, a.pp};
  const std::uint8_t* qrows[3] = {a.qm, a.q0, a.qp};
  float nb[3][3];
  std::uint8_t qn[3][3];
  for (int dc = 0; dc < 3; ++dc)
    for (int db = 0; db < 3; ++db) {
      const int j = i + db - 1;
      const bool inside = j >= 0 && j < a.n;
      nb[dc][db] = inside ? rows[dc][j] : kInf;
      qn[dc][db] = inside ? qrows[dc][j] : 0;
    }
  const float v = relaxVoxel<K>(a.cur[i], nb, qn, a.qc[i], a.l, a.base);
  const int changed = v < a.cur[i];
  a.cur[i] = v;
  return changed;
}

// The interior of a row, written for the auto-vectoriser: restrict parameters (GCC trusts those,
// not restrict locals; without them it versions the loop on an overlap test that adjacent planes
// fail), no branches (minf is a compare-select, i.e. minps).
template <CostKernel K>
AT_ALWAYS_INLINE int rowInterior(float* __restrict cur, const float* __restrict pm, const float* __restrict p0,
                                 const float* __restrict pp, const std::uint8_t* __restrict qc,
                                 const std::uint8_t* __restrict qm, const std::uint8_t* __restrict q0,
                                 const std::uint8_t* __restrict qp, int last, SweepLengths l, float base) {
  int changed = 0;
#pragma GCC ivdep
  for (int i = 1; i < last; ++i) {
    const float nb[3][3] = {{pm[i - 1], pm[i], pm[i + 1]}, {p0[i - 1], p0[i], p0[i + 1]}, {pp[i - 1], pp[i], pp[i + 1]}};
    const std::uint8_t qn[3][3] = {
        {qm[i - 1], qm[i], qm[i + 1]}, {q0[i - 1], q0[i], q0[i + 1]}, {qp[i - 1], qp[i], qp[i + 1]}};
    const float c = cur[i];
    const float v = relaxVoxel<K>(c, nb, qn, qc[i], l, base);
    // v <= c always, so "lowered" is "bits differ"; an integer test keeps the loop branch-free
    // (a float compare here stops GCC 12 from vectorising the enteringUpdate kernels).
    changed |= __builtin_bit_cast(int, v) ^ __builtin_bit_cast(int, c);
    cur[i] = v;
  }
  return changed != 0;
}

template <CostKernel K>
AT_ALWAYS_INLINE int rowLoop(const RowArgs& a) {
  int changed = relaxEdge<K>(a, 0);
  if (a.n == 1) return changed;
  changed |= rowInterior<K>(a.cur, a.pm, a.p0, a.pp, a.qc, a.qm, a.q0, a.qp, a.n - 1, a.l, a.base);
  return changed | relaxEdge<K>(a, a.n - 1);
}

template <CostKernel K>
__attribute__((target("avx2"), noinline)) int rowAvx2(const RowArgs& a) {
  return rowLoop<K>(a);
}

template <CostKernel K>
__attribute__((noinline)) int rowBaseline(const RowArgs& a) {
  return rowLoop<K>(a);
}

using RowFn = int (*)(const RowArgs&);

template <CostKernel K>
RowFn pickRow(bool avx2) {
  return avx2 ? &rowAvx2<K> : &rowBaseline<K>;
}

RowFn rowFunction(CostKernel k) {
  const bool avx2 = __builtin_cpu_supports("avx2");
  switch (k) {
    case CostKernel::EnterDensity: return pickRow<CostKernel::EnterDensity>(avx2);
    case CostKernel::EnterUniform: return pickRow<CostKernel::EnterUniform>(avx2);
    case CostKernel::TrapezoidDensity: return pickRow<CostKernel::TrapezoidDensity>(avx2);
    case CostKernel::EdgeGradient: return pickRow<CostKernel::EdgeGradient>(avx2);
    case CostKernel::EdgeAscent: return pickRow<CostKernel::EdgeAscent>(avx2);
  }
  return nullptr;
}

// ─────────────────────────────────────────────────────────────────────────────────────────────
// [SECTION] Team
// ─────────────────────────────────────────────────────────────────────────────────────────────

// Generation-counting barrier. Spins briefly (an idle machine's planes take tens of
// microseconds), then sleeps on the generation word (futex): on a loaded machine the partner may
// be descheduled, and a sleeping waiter hands it the core instead of competing for it.
class SpinBarrier {
 public:
  explicit SpinBarrier(int n) : n_(n) {}
  void wait() {
    if (n_ == 1) return;
    const unsigned gen = generation_.load(std::memory_order_acquire);
    if (count_.fetch_add(1, std::memory_order_acq_rel) == n_ - 1) {
      count_.store(0, std::memory_order_relaxed);
      generation_.fetch_add(1, std::memory_order_acq_rel);
      generation_.notify_all();
      return;
    }
    for (int spin = 0; spin < 2000; ++spin) {
      if (generation_.load(std::memory_order_acquire) != gen) return;
      __builtin_ia32_pause();
    }
    while (generation_.load(std::memory_order_acquire) == gen) generation_.wait(gen, std::memory_order_acquire);
  }

 private:
  const int n_;
  std::atomic<int> count_{0};
  std::atomic<unsigned> generation_{0};
};

// How a sweep sees an array: `planes` planes of `rows` rows of `rowLen` contiguous voxels.
struct SweepGeometry {
  std::size_t planeStride = 0, rowStride = 0;
  int rowLen = 0, rows = 0, planes = 0;
  SweepLengths lengths{};
};

// ─────────────────────────────────────────────────────────────────────────────────────────────
// [SECTION] Schedule
// ─────────────────────────────────────────────────────────────────────────────────────────────

struct Run {
  const WdtProblem& problem;
  const WdtControl& control;
  int threads = 1;
  RowFn row = nullptr;
  float base = 0;
  Dims dims;
  std::vector<float> d;          // L1: x contiguous
  std::unique_ptr<float[]> dT;         // L2: y contiguous (x sweeps); first touched by the team
  std::unique_ptr<std::uint8_t[]> qT;  // density bytes in L2
  std::vector<float> infRow;
  std::vector<std::uint8_t> zeroRow;
  SweepGeometry x, y, z;

  SpinBarrier barrier;
  std::vector<int> changedBy;    // per thread, this pass
  bool stop = false;             // written by thread 0 between barriers
  bool more = true;
  int passesRun = 0;
  bool lastChanged = true;
  bool cancelled = false;
  std::vector<double> msPerPass;

  Run(const WdtProblem& p, const WdtControl& c, int t) : problem(p), control(c), threads(t), barrier(t) {}
};

// Transposes z slices [z0, z1) of a (w × h × depth) array with w contiguous into h contiguous.
template <class T>
void transposeSlicesScalar(const T* src, T* dst, int w, int h, int z0, int z1) {
  constexpr int B = 32;
  const std::size_t slice = std::size_t(w) * h;
  for (int z = z0; z < z1; ++z) {
    const T* s = src + slice * z;
    T* t = dst + slice * z;
    for (int y0 = 0; y0 < h; y0 += B)
      for (int x0 = 0; x0 < w; x0 += B) {
        const int y1 = std::min(h, y0 + B), x1 = std::min(w, x0 + B);
        for (int x = x0; x < x1; ++x)
          for (int y = y0; y < y1; ++y) t[y + std::size_t(h) * x] = s[x + std::size_t(w) * y];
      }
  }
}

// The float version moves 8×8 tiles through AVX registers (unpack/shuffle/permute network).
__attribute__((target("avx2"))) void transposeFloatAvx2(const float* src, float* dst, int w, int h, int z0, int z1) {
  const std::size_t slice = std::size_t(w) * h;
  const int w8 = w & ~7, h8 = h & ~7;
  for (int z = z0; z < z1; ++z) {
    const float* s = src + slice * z;
    float* t = dst + slice * z;
    for (int y0 = 0; y0 < h8; y0 += 8)
      for (int x0 = 0; x0 < w8; x0 += 8) {
        __m256 r[8], u[8], v[8];
        for (int k = 0; k < 8; ++k) r[k] = _mm256_loadu_ps(s + x0 + std::size_t(w) * (y0 + k));
        for (int k = 0; k < 4; ++k) {
          u[2 * k] = _mm256_unpacklo_ps(r[2 * k], r[2 * k + 1]);
          u[2 * k + 1] = _mm256_unpackhi_ps(r[2 * k], r[2 * k + 1]);
        }
        for (int k = 0; k < 2; ++k) {
          v[4 * k + 0] = _mm256_shuffle_ps(u[4 * k], u[4 * k + 2], _MM_SHUFFLE(1, 0, 1, 0));
          v[4 * k + 1] = _mm256_shuffle_ps(u[4 * k], u[4 * k + 2], _MM_SHUFFLE(3, 2, 3, 2));
          v[4 * k + 2] = _mm256_shuffle_ps(u[4 * k + 1], u[4 * k + 3], _MM_SHUFFLE(1, 0, 1, 0));
          v[4 * k + 3] = _mm256_shuffle_ps(u[4 * k + 1], u[4 * k + 3], _MM_SHUFFLE(3, 2, 3, 2));
        }
        for (int k = 0; k < 4; ++k) {
          r[k] = _mm256_permute2f128_ps(v[k], v[k + 4], 0x20);
          r[k + 4] = _mm256_permute2f128_ps(v[k], v[k + 4], 0x31);
        }
        for (int k = 0; k < 8; ++k) _mm256_storeu_ps(t + y0 + std::size_t(h) * (x0 + k), r[k]);
      }
    // Ragged edges (w or h not a multiple of 8).
    for (int y = 0; y < h; ++y)
      for (int x = (y < h8 ? w8 : 0); x < w; ++x) t[y + std::size_t(h) * x] = s[x + std::size_t(w) * y];
  }
}

template <class T>
void transposeSlices(const T* src, T* dst, int w, int h, int z0, int z1) {
  if constexpr (std::is_same_v<T, float>) {
    static const bool avx2 = __builtin_cpu_supports("avx2");
    if (avx2) return transposeFloatAvx2(src, dst, w, h, z0, z1);
  }
  transposeSlicesScalar(src, dst, w, h, z0, z1);
}

void sweep(Run& run, const SweepGeometry& g, float* dist, const std::uint8_t* q, int dir, int tid) {
  const int r0 = int(std::int64_t(g.rows) * tid / run.threads);
  const int r1 = int(std::int64_t(g.rows) * (tid + 1) / run.threads);
  int changed = 0;
  RowArgs a{};
  a.n = g.rowLen;
  a.l = g.lengths;
  a.base = run.base;
  for (int step = 1; step < g.planes; ++step) {
    const int p = dir > 0 ? step : g.planes - 1 - step;
    const int prev = p - dir;
    float* plane = dist + g.planeStride * p;
    const float* prevPlane = dist + g.planeStride * prev;
    const std::uint8_t* qPlane = q + g.planeStride * p;
    const std::uint8_t* qPrev = q + g.planeStride * prev;
    for (int r = r0; r < r1; ++r) {
      a.cur = plane + g.rowStride * r;
      a.qc = qPlane + g.rowStride * r;
      a.p0 = prevPlane + g.rowStride * r;
      a.q0 = qPrev + g.rowStride * r;
      a.pm = r > 0 ? a.p0 - g.rowStride : run.infRow.data();
      a.qm = r > 0 ? a.q0 - g.rowStride : run.zeroRow.data();
      a.pp = r + 1 < g.rows ? a.p0 + g.rowStride : run.infRow.data();
      a.qp = r + 1 < g.rows ? a.q0 + g.rowStride : run.zeroRow.data();
      changed |= run.row(a);
    }
    run.barrier.wait();
  }
  run.changedBy[tid] |= changed;
}

// Thread 0 samples the cancel flag between two barriers so that every thread takes the same
// decision. Returns true when the run must stop.
bool checkCancel(Run& run, int tid) {
  run.barrier.wait();
  if (tid == 0) run.stop = run.control.cancel && run.control.cancel->load(std::memory_order_relaxed);
  run.barrier.wait();
  return run.stop;
}

void worker(Run& run, int tid) {
  const Dims d = run.dims;
  const int zs0 = int(std::int64_t(d.z) * tid / run.threads), zs1 = int(std::int64_t(d.z) * (tid + 1) / run.threads);
  const std::uint8_t* q = run.problem.density.data();
  const int planned = run.problem.params.converge ? run.problem.params.maxPasses : run.problem.params.passes;
  {
    const std::size_t slice = std::size_t(d.x) * d.y;
    const std::uint8_t* seeds = run.problem.seeds.data();
    for (std::size_t i = slice * zs0; i < slice * zs1; ++i) run.d[i] = seeds[i] ? 0.0f : kInf;
    transposeSlices(q, run.qT.get(), d.x, d.y, zs0, zs1);
  }
  for (int pass = 0; pass < planned; ++pass) {
    const auto t0 = std::chrono::steady_clock::now();
    run.changedBy[tid] = 0;
    if (checkCancel(run, tid)) break;
    transposeSlices(run.d.data(), run.dT.get(), d.x, d.y, zs0, zs1);
    run.barrier.wait();
    sweep(run, run.x, run.dT.get(), run.qT.get(), +1, tid);
    if (checkCancel(run, tid)) {
      transposeSlices(run.dT.get(), run.d.data(), d.y, d.x, zs0, zs1);  // keep the partial x+ result
      run.barrier.wait();
      break;
    }
    sweep(run, run.x, run.dT.get(), run.qT.get(), -1, tid);
    transposeSlices(run.dT.get(), run.d.data(), d.y, d.x, zs0, zs1);
    if (checkCancel(run, tid)) break;
    sweep(run, run.y, run.d.data(), q, +1, tid);
    if (checkCancel(run, tid)) break;
    sweep(run, run.y, run.d.data(), q, -1, tid);
    if (checkCancel(run, tid)) break;
    sweep(run, run.z, run.d.data(), q, +1, tid);
    if (checkCancel(run, tid)) break;
    sweep(run, run.z, run.d.data(), q, -1, tid);
    run.barrier.wait();
    if (tid == 0) {
      bool changed = false;
      for (int c : run.changedBy) changed = changed || c;
      run.lastChanged = changed;
      run.passesRun = pass + 1;
      run.msPerPass.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
      if (run.control.progress) run.control.progress(pass + 1, planned);
      run.more = !(run.problem.params.converge && !changed);
    }
    run.barrier.wait();
    if (!run.more) break;
  }
  if (tid == 0) run.cancelled = run.stop;
}

}  // namespace

Result<WdtResult> runCpuBackend(const WdtProblem& problem, const WdtControl& control) {
  const auto t0 = std::chrono::steady_clock::now();
  const Geometry& grid = problem.grid;
  const Dims d = grid.dims;
  if (d.count() == 0 || problem.density.size() != d.count() || problem.seeds.size() != d.count())
    return fail("WDT CPU backend: problem arrays do not match the grid " + d.toString());
  if (auto ok = validateWdtParams(problem.params); !ok) return tl::unexpected(ok.error());

  const int hw = int(std::max(1u, std::thread::hardware_concurrency()));
  // Threads meet at a barrier after every plane; below ~32K voxels per plane (128² and smaller)
  // a plane's work is shorter than a barrier round trip and one thread is faster.
  const std::size_t planeVoxels = d.count() / std::size_t(std::max({d.x, d.y, d.z}));
  int threads = int(std::min<std::size_t>(std::size_t(hw), std::max<std::size_t>(1, planeVoxels / 32768)));
  // AT_WDT_THREADS=N forces N threads (benchmarks, and tests of the multi-threaded schedule).
  if (const char* env = std::getenv("AT_WDT_THREADS")) threads = std::clamp(std::atoi(env), 1, 256);
  Run run(problem, control, threads);
  run.dims = d;
  run.base = problem.params.baseCost;
  run.row = rowFunction(wdt::costKernel(problem.params));
  wdt::resizeOnHugePages(run.d, d.count());
  run.dT.reset(wdt::newOnHugePages<float>(d.count()));
  run.qT.reset(wdt::newOnHugePages<std::uint8_t>(d.count()));
  const int longest = std::max({d.x, d.y, d.z});
  run.infRow.assign(std::size_t(longest), kInf);
  run.zeroRow.assign(std::size_t(longest), 0);
  run.changedBy.assign(std::size_t(threads), 0);

  const float sx = float(grid.spacingMm[0]), sy = float(grid.spacingMm[1]), sz = float(grid.spacingMm[2]);
  const std::size_t nxy = std::size_t(d.x) * d.y;
  // L2 (y contiguous): planes x, rows z.        L1 (x contiguous): y sweep planes y, rows z;
  run.x = {std::size_t(d.y), nxy, d.y, d.z, d.x, wdt::axisSweepLengths(0, sx, sy, sz)};
  run.y = {std::size_t(d.x), nxy, d.x, d.z, d.y, wdt::axisSweepLengths(1, sx, sy, sz)};
  // z sweep planes z, rows y.
  run.z = {nxy, std::size_t(d.x), d.x, d.y, d.z, wdt::axisSweepLengths(2, sx, sy, sz)};

  std::vector<std::thread> team;
  team.reserve(std::size_t(threads - 1));
  for (int t = 1; t < threads; ++t) team.emplace_back([&run, t] { worker(run, t); });
  worker(run, 0);
  for (std::thread& t : team) t.join();

  WdtResult result;
  result.field.distances.geometry = grid;
  result.field.distances.voxels = std::move(run.d);
  result.field.downsample = problem.params.downsample;
  WdtStats& s = result.stats;
  s.passesRun = run.passesRun;
  s.converged = run.passesRun > 0 && !run.lastChanged && !run.cancelled;
  s.cancelled = run.cancelled;
  s.msPerPass = std::move(run.msPerPass);
  s.backendUsed = WdtBackend::Cpu;
  s.device = "CPU (" + std::to_string(threads) + (threads == 1 ? " thread)" : " threads)");
  s.msTotal = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace at
