// The CPU backend: the paper's multi-axis sweeps (Algorithm 2), multi-threaded and vectorised.
//
// [SECTION] Row kernel   a thread's rows of one plane, vectorised along the contiguous axis (AVX2 or SSE2)
// [SECTION] Team         a spin barrier and the per-plane split of rows among threads
// [SECTION] Schedule     one pass = x+ x− y+ y− z+ z−, transposes, convergence, cancellation
//
// Layout: D is kept with i (x) contiguous ("L1"). The y and z sweeps then have planes that
// contain whole x rows: each thread takes a share of the plane's rows, each row is one vectorised
// loop over x, and the threads meet at a barrier after every plane (the next plane reads this one).
// The x sweeps run across the contiguous axis; instead of strided or gathered access, D is
// transposed per z slice into an "L2" copy with j (y) contiguous, where the x sweeps are again
// sweeps of whole rows (rows along y), and transposed back (see worker() for which transposes are
// folded into sweeps). The density bytes are transposed once per run, with the seeds.
// Under the entering rule (AVX2) two rows of a plane are swept together, sharing the loads and
// lateral minima of the previous plane's rows (enteringPairAvx2).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <type_traits>
#include <immintrin.h>
#include <utility>
#include <vector>

#include "wdt/huge_pages.h"
#include "wdt/step_cost.h"
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
  const float v = wdt::relaxVoxel<K>(a.cur[i], nb, qn, a.qc[i], a.l, a.base);
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
    const float v = wdt::relaxVoxel<K>(c, nb, qn, qc[i], l, base);
    // v <= c always, so "lowered" is "bits differ"; an integer test keeps the loop branch-free
    // (a float compare here stops GCC 12 from vectorising the enteringUpdate kernels).
    changed |= __builtin_bit_cast(int, v) ^ __builtin_bit_cast(int, c);
    cur[i] = v;
  }
  return changed != 0;
}

// Two adjacent rows r, r + 1 of the current plane under the entering rule, hand-vectorised (AVX2,
// 8 voxels per step): they read the previous plane's rows r − 1 … r + 2 (p0..p3). Each previous
// row is loaded once and its lateral minimum min(p[i − 1], p[i + 1]) computed once for both
// voxels; the mins are exact, so regrouping them changes nothing, and every add and multiply is
// enteringUpdate's, on the same operands (no FMA). Voxels [1, last) of both rows; returns whether
// any voxel changed. GCC's own vectorisation of a two-row loop unrolls it 4× and spills (slower
// than one row at a time), hence intrinsics.
#define AT_AVX2_INLINE __attribute__((target("avx2"), always_inline)) inline

AT_AVX2_INLINE __m256 lateralMin(const float* p) {
  return _mm256_min_ps(_mm256_loadu_ps(p - 1), _mm256_loadu_ps(p + 1));
}

// densityWeight for 8 voxels: base + q · (1/255).
AT_AVX2_INLINE __m256 densityWeights(const std::uint8_t* q, __m256 base, __m256 scale) {
  const __m256 d = _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(q))));
  return _mm256_add_ps(base, _mm256_mul_ps(d, scale));
}

// enteringUpdate of 8 voxels at c: m00 = straight, m10 = along the row, m01 = across rows,
// m11 = diagonal neighbours' minimum. Accumulates "bits changed" into `changed`.
AT_AVX2_INLINE void enteringUpdate8(float* c, __m256 m00, __m256 m10, __m256 m01, __m256 m11, __m256 w, __m256 ls,
                                    __m256 lb, __m256 lc, __m256 ld, __m256i& changed) {
  const __m256 cand = _mm256_min_ps(
      _mm256_min_ps(_mm256_add_ps(m00, _mm256_mul_ps(w, ls)), _mm256_add_ps(m10, _mm256_mul_ps(w, lb))),
      _mm256_min_ps(_mm256_add_ps(m01, _mm256_mul_ps(w, lc)), _mm256_add_ps(m11, _mm256_mul_ps(w, ld))));
  const __m256 cur = _mm256_loadu_ps(c);
  const __m256 v = _mm256_min_ps(cur, cand);
  changed = _mm256_or_si256(changed, _mm256_castps_si256(_mm256_xor_ps(v, cur)));
  _mm256_storeu_ps(c, v);
}

// Voxel i of a row pair: c0[i] from its neighbours nbA, c1[i] from nbB (enteringUpdate). Returns
// the bits that changed in either voxel (0 when neither changed).
template <bool Uniform>
AT_ALWAYS_INLINE int enteringPairVoxel(float* c0, float* c1, const float nbA[3][3], const float nbB[3][3],
                                       const std::uint8_t* q0, const std::uint8_t* q1, int i, SweepLengths l,
                                       float base) {
  const float wa = Uniform ? 1.0f : wdt::densityWeight(q0[i], base);
  const float wb = Uniform ? 1.0f : wdt::densityWeight(q1[i], base);
  const float va = wdt::enteringUpdate(c0[i], nbA, wa, l), vb = wdt::enteringUpdate(c1[i], nbB, wb, l);
  const int changed = (__builtin_bit_cast(int, va) ^ __builtin_bit_cast(int, c0[i])) |
                      (__builtin_bit_cast(int, vb) ^ __builtin_bit_cast(int, c1[i]));
  c0[i] = va;
  c1[i] = vb;
  return changed;
}

template <bool Uniform>
__attribute__((target("avx2"), noinline)) int enteringPairAvx2(float* c0, float* c1, const float* p0,
                                                               const float* p1, const float* p2, const float* p3,
                                                               const std::uint8_t* q0, const std::uint8_t* q1,
                                                               int last, SweepLengths l, float base, bool down) {
  const __m256 ls = _mm256_set1_ps(l.straight), lb = _mm256_set1_ps(l.alongB);
  const __m256 lc = _mm256_set1_ps(l.alongC), ld = _mm256_set1_ps(l.diagonal);
  const __m256 vbase = _mm256_set1_ps(base), scale = _mm256_set1_ps(1.0f / 255.0f), one = _mm256_set1_ps(1.0f);
  __m256i changed = _mm256_setzero_si256();
  // Downwards (descending i), memory is walked the way a downward sweep goes: a row's start
  // borders on the same row of the next plane (x and y sweeps) and the hardware prefetcher's
  // stream runs on into it.
  const int vectorEnd = 1 + (last - 1) / 8 * 8;
  for (int k = 0; k + 1 < vectorEnd; k += 8) {
    const int i = down ? vectorEnd - 8 - k : 1 + k;
    const __m256 l0 = lateralMin(p0 + i), s0 = _mm256_loadu_ps(p0 + i);
    const __m256 l1 = lateralMin(p1 + i), s1 = _mm256_loadu_ps(p1 + i);
    const __m256 l2 = lateralMin(p2 + i), s2 = _mm256_loadu_ps(p2 + i);
    const __m256 w0 = Uniform ? one : densityWeights(q0 + i, vbase, scale);
    enteringUpdate8(c0 + i, s1, l1, _mm256_min_ps(s0, s2), _mm256_min_ps(l0, l2), w0, ls, lb, lc, ld, changed);
    const __m256 l3 = lateralMin(p3 + i), s3 = _mm256_loadu_ps(p3 + i);
    const __m256 w1 = Uniform ? one : densityWeights(q1 + i, vbase, scale);
    enteringUpdate8(c1 + i, s2, l2, _mm256_min_ps(s1, s3), _mm256_min_ps(l1, l3), w1, ls, lb, lc, ld, changed);
  }
  int tail = 0;
  for (int i = vectorEnd; i < last; ++i) {
    const float nbA[3][3] = {
        {p0[i - 1], p0[i], p0[i + 1]}, {p1[i - 1], p1[i], p1[i + 1]}, {p2[i - 1], p2[i], p2[i + 1]}};
    const float nbB[3][3] = {
        {p1[i - 1], p1[i], p1[i + 1]}, {p2[i - 1], p2[i], p2[i + 1]}, {p3[i - 1], p3[i], p3[i + 1]}};
    tail |= enteringPairVoxel<Uniform>(c0, c1, nbA, nbB, q0, q1, i, l, base);
  }
  return tail != 0 || !_mm256_testz_si256(changed, changed);
}

// The two ends (i = 0 and i = n − 1, n ≥ 2) of the row pair of enteringPairAvx2, with +infinity
// beyond the row as relaxEdge: the same values and float operations, without its general loops.
template <bool Uniform>
__attribute__((noinline)) int enteringPairEnds(float* c0, float* c1, const float* p0, const float* p1, const float* p2,
                                               const float* p3, const std::uint8_t* q0, const std::uint8_t* q1, int n,
                                               SweepLengths l, float base) {
  int changed = 0;
  for (const int i : {0, n - 1}) {
    const float* rows[4] = {p0, p1, p2, p3};
    float lo[4], mid[4], hi[4];
    for (int k = 0; k < 4; ++k) {
      lo[k] = i > 0 ? rows[k][i - 1] : kInf;
      mid[k] = rows[k][i];
      hi[k] = i + 1 < n ? rows[k][i + 1] : kInf;
    }
    const float nbA[3][3] = {{lo[0], mid[0], hi[0]}, {lo[1], mid[1], hi[1]}, {lo[2], mid[2], hi[2]}};
    const float nbB[3][3] = {{lo[1], mid[1], hi[1]}, {lo[2], mid[2], hi[2]}, {lo[3], mid[3], hi[3]}};
    changed |= enteringPairVoxel<Uniform>(c0, c1, nbA, nbB, q0, q1, i, l, base);
  }
  return changed != 0;
}

// The rows [r0, r1) of one plane, pairs first. A row outside the plane is +infinity (zeroRow
// for its density bytes).
struct PlaneArgs {
  float* plane;
  const float* prevPlane;
  const std::uint8_t* qPlane;
  const std::uint8_t* qPrev;
  std::size_t rowStride;
  int rows, r0, r1, n;
  SweepLengths l;
  float base;
  const float* infRow;
  const std::uint8_t* zeroRow;
  std::ptrdiff_t prefetchAhead;  // nonzero: fetch the rows this far away (the next plane) into L2
  bool down;                     // a downward sweep: walk rows and voxels downwards
};

template <CostKernel K, bool Avx2>
AT_ALWAYS_INLINE int planeLoop(const PlaneArgs& pa) {
  constexpr bool pairs = Avx2 && (K == CostKernel::EnterDensity || K == CostKernel::EnterUniform);
  auto prevRow = [&](int r) { return r >= 0 && r < pa.rows ? pa.prevPlane + pa.rowStride * r : pa.infRow; };
  auto prevQ = [&](int r) { return r >= 0 && r < pa.rows ? pa.qPrev + pa.rowStride * r : pa.zeroRow; };
  auto fetchNext = [&](const float* row, const std::uint8_t* qrow) {
    if (!pa.prefetchAhead) return;
    const char* nd = reinterpret_cast<const char*>(row + pa.prefetchAhead);
    const char* nq = reinterpret_cast<const char*>(qrow + pa.prefetchAhead);
    for (int o = 0; o < pa.n * int(sizeof(float)); o += 64) _mm_prefetch(nd + o, _MM_HINT_T1);
    for (int o = 0; o < pa.n; o += 64) _mm_prefetch(nq + o, _MM_HINT_T1);
  };
  int changed = 0;
  RowArgs a{};
  a.n = pa.n;
  a.l = pa.l;
  a.base = pa.base;
  auto edges = [&](int r) {
    a.cur = pa.plane + pa.rowStride * r;
    a.qc = pa.qPlane + pa.rowStride * r;
    a.pm = prevRow(r - 1), a.p0 = prevRow(r), a.pp = prevRow(r + 1);
    a.qm = prevQ(r - 1), a.q0 = prevQ(r), a.qp = prevQ(r + 1);
    changed |= relaxEdge<K>(a, 0);
    if (a.n > 1) changed |= relaxEdge<K>(a, a.n - 1);
  };
  int r = pa.r0;
  if constexpr (pairs) {
    // Downward sweeps take the pairs from the last row up (see enteringPairAvx2); an odd row left
    // over (r1 − 1) is done below.
    const int pairsEnd = pa.r0 + (pa.r1 - pa.r0) / 2 * 2;
    for (int k = 0; k < pairsEnd - pa.r0; k += 2) {
      const int r = pa.down ? pairsEnd - 2 - k : pa.r0 + k;
      float* c0 = pa.plane + pa.rowStride * r;
      const std::uint8_t* qc0 = pa.qPlane + pa.rowStride * r;
      fetchNext(c0, qc0);
      fetchNext(c0 + pa.rowStride, qc0 + pa.rowStride);
      if (pa.n > 2) {
        constexpr bool uniform = K == CostKernel::EnterUniform;
        const float *p0 = prevRow(r - 1), *p1 = prevRow(r), *p2 = prevRow(r + 1), *p3 = prevRow(r + 2);
        float* c1 = c0 + pa.rowStride;
        const std::uint8_t* qc1 = qc0 + pa.rowStride;
        changed |= enteringPairAvx2<uniform>(c0, c1, p0, p1, p2, p3, qc0, qc1, pa.n - 1, pa.l, pa.base, pa.down);
        changed |= enteringPairEnds<uniform>(c0, c1, p0, p1, p2, p3, qc0, qc1, pa.n, pa.l, pa.base);
      } else {
        edges(r);
        edges(r + 1);
      }
    }
    r = pairsEnd;
  }
  for (; r < pa.r1; ++r) {
    float* c0 = pa.plane + pa.rowStride * r;
    const std::uint8_t* qc0 = pa.qPlane + pa.rowStride * r;
    fetchNext(c0, qc0);
    if (pa.n > 2)
      changed |= rowInterior<K>(c0, prevRow(r - 1), prevRow(r), prevRow(r + 1), qc0, prevQ(r - 1), prevQ(r),
                                prevQ(r + 1), pa.n - 1, pa.l, pa.base);
    edges(r);
  }
  return changed;
}

template <CostKernel K>
__attribute__((target("avx2"), noinline)) int planeAvx2(const PlaneArgs& a) {
  return planeLoop<K, true>(a);
}

template <CostKernel K>
__attribute__((noinline)) int planeBaseline(const PlaneArgs& a) {
  return planeLoop<K, false>(a);
}

using PlaneFn = int (*)(const PlaneArgs&);

PlaneFn planeFunction(CostKernel k, bool avx2) {
  return wdt::withCostKernel(k, [avx2]<CostKernel K>() -> PlaneFn { return avx2 ? &planeAvx2<K> : &planeBaseline<K>; });
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
  PlaneFn plane = nullptr;
  bool avx2 = false;             // AVX2 row kernels, transposes and initialisation
  float base = 0;
  Dims dims;
  std::vector<float> d;          // L1: x contiguous; allocated by thread 0 of the team
  std::unique_ptr<float[]> dT;         // L2: y contiguous (x sweeps); first touched by the team
  std::unique_ptr<std::uint8_t[]> qT;  // density bytes in L2
  std::vector<float> infRow;
  std::vector<std::uint8_t> zeroRow;
  SweepGeometry x, y, z;

  SpinBarrier barrier;
  std::atomic<int> nextSlice{0}; // next z slice to initialise
  std::vector<int> changedBy;    // per thread, this pass
  bool stop = false;             // written by thread 0 between barriers
  bool more = true;
  int passesRun = 0;
  bool lastChanged = true;
  bool cancelled = false;
  std::vector<double> msPerPass;

  Run(const WdtProblem& p, const WdtControl& c, int t) : problem(p), control(c), threads(t), barrier(t) {}
};

// ─── Transposes ───
// A slice is w × h with w contiguous; its transpose has h contiguous: t[y + h·x] = s[x + w·y].
// The functions below transpose the source rows y ∈ [y0, y1) of one slice, so that a thread can
// transpose just the rows it has swept (still in its caches) or a block of planes.

template <class T>
void transposeRowsScalar(const T* s, T* t, int w, int h, int y0, int y1) {
  constexpr int B = 32;
  for (int yb = y0; yb < y1; yb += B)
    for (int xb = 0; xb < w; xb += B) {
      const int ye = std::min(y1, yb + B), xe = std::min(w, xb + B);
      for (int x = xb; x < xe; ++x)
        for (int y = yb; y < ye; ++y) t[y + std::size_t(h) * x] = s[x + std::size_t(w) * y];
    }
}

// 8×8 float tiles through AVX registers (unpack/shuffle/permute network), ragged edges scalar.
__attribute__((target("avx2"))) void transposeRowsFloatAvx2(const float* s, float* t, int w, int h, int y0, int y1) {
  const int w8 = w & ~7;
  const int y8 = y0 + ((y1 - y0) & ~7);
  for (int xb = 0; xb < w8; xb += 8)
    for (int yb = y0; yb < y8; yb += 8) {
      __m256 r[8], u[8], v[8];
      for (int k = 0; k < 8; ++k) r[k] = _mm256_loadu_ps(s + xb + std::size_t(w) * (yb + k));
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
      for (int k = 0; k < 8; ++k) _mm256_storeu_ps(t + yb + std::size_t(h) * (xb + k), r[k]);
    }
  for (int y = y0; y < y1; ++y)
    for (int x = (y < y8 ? w8 : 0); x < w; ++x) t[y + std::size_t(h) * x] = s[x + std::size_t(w) * y];
}

void transposeRows(const float* s, float* t, int w, int h, int y0, int y1, bool avx2) {
  if (avx2) return transposeRowsFloatAvx2(s, t, w, h, y0, y1);
  transposeRowsScalar(s, t, w, h, y0, y1);
}

// Whole z slices [z0, z1) of a (w × h × depth) array.
void transposeSlices(const float* src, float* dst, int w, int h, int z0, int z1, bool avx2) {
  const std::size_t slice = std::size_t(w) * h;
  for (int z = z0; z < z1; ++z) transposeRows(src + slice * z, dst + slice * z, w, h, 0, h, avx2);
}

// The starting state of one z slice, produced directly in the x sweeps' layout: dT = transposed
// (seed ? 0 : +∞) and qT = transposed density bytes. The same values as initialising D in L1 and
// transposing it, without the L1 pass.
void initSliceScalar(const std::uint8_t* seeds, const std::uint8_t* q, float* dT, std::uint8_t* qT, int w, int h,
                     int y0, int y1, int x0) {
  constexpr int B = 32;
  for (int yb = y0; yb < y1; yb += B)
    for (int xb = x0; xb < w; xb += B) {
      const int ye = std::min(y1, yb + B), xe = std::min(w, xb + B);
      for (int x = xb; x < xe; ++x)
        for (int y = yb; y < ye; ++y) {
          const std::size_t from = x + std::size_t(w) * y, to = y + std::size_t(h) * x;
          dT[to] = seeds[from] ? 0.0f : kInf;
          qT[to] = q[from];
        }
    }
}

// 8×8 byte tiles: returns in out[j] the tile's columns 2j (low 8 bytes) and 2j + 1 (high 8 bytes).
AT_ALWAYS_INLINE void transposeBytes8x8(const std::uint8_t* s, std::size_t stride, __m128i out[4]) {
  __m128i r[8];
  for (int k = 0; k < 8; ++k) r[k] = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(s + stride * k));
  const __m128i t0 = _mm_unpacklo_epi8(r[0], r[1]), t1 = _mm_unpacklo_epi8(r[2], r[3]);
  const __m128i t2 = _mm_unpacklo_epi8(r[4], r[5]), t3 = _mm_unpacklo_epi8(r[6], r[7]);
  const __m128i u0 = _mm_unpacklo_epi16(t0, t1), u1 = _mm_unpackhi_epi16(t0, t1);
  const __m128i u2 = _mm_unpacklo_epi16(t2, t3), u3 = _mm_unpackhi_epi16(t2, t3);
  out[0] = _mm_unpacklo_epi32(u0, u2);
  out[1] = _mm_unpackhi_epi32(u0, u2);
  out[2] = _mm_unpacklo_epi32(u1, u3);
  out[3] = _mm_unpackhi_epi32(u1, u3);
}

__attribute__((target("avx2"))) void initSliceAvx2(const std::uint8_t* seeds, const std::uint8_t* q, float* dT,
                                                   std::uint8_t* qT, int w, int h) {
  const int w8 = w & ~7, h8 = h & ~7;
  const __m256 inf = _mm256_set1_ps(kInf);
  const __m256i zero = _mm256_setzero_si256();
  for (int yb = 0; yb < h8; yb += 8)
    for (int xb = 0; xb < w8; xb += 8) {
      __m128i qc[4], sc[4];
      transposeBytes8x8(q + xb + std::size_t(w) * yb, std::size_t(w), qc);
      transposeBytes8x8(seeds + xb + std::size_t(w) * yb, std::size_t(w), sc);
      for (int j = 0; j < 4; ++j) {
        std::uint8_t* q0 = qT + yb + std::size_t(h) * (xb + 2 * j);
        _mm_storel_epi64(reinterpret_cast<__m128i*>(q0), qc[j]);
        _mm_storel_epi64(reinterpret_cast<__m128i*>(q0 + h), _mm_unpackhi_epi64(qc[j], qc[j]));
        for (int half = 0; half < 2; ++half) {
          const __m128i bytes = half ? _mm_unpackhi_epi64(sc[j], sc[j]) : sc[j];
          const __m256i notSeed = _mm256_cmpeq_epi32(_mm256_cvtepu8_epi32(bytes), zero);
          const __m256 d = _mm256_and_ps(inf, _mm256_castsi256_ps(notSeed));  // seed ? +0 : +∞
          _mm256_storeu_ps(dT + yb + std::size_t(h) * (xb + 2 * j + half), d);
        }
      }
    }
  initSliceScalar(seeds, q, dT, qT, w, h, 0, h8, w8);  // right edge of the full row blocks
  initSliceScalar(seeds, q, dT, qT, w, h, h8, h, 0);   // bottom rows
}

void initSlice(const std::uint8_t* seeds, const std::uint8_t* q, float* dT, std::uint8_t* qT, int w, int h,
               bool avx2) {
  if (avx2) return initSliceAvx2(seeds, q, dT, qT, w, h);
  initSliceScalar(seeds, q, dT, qT, w, h, 0, h, 0);
}

// ─── Sweeps ───

struct NoHook {
  void operator()(int, int, int) const {}
};

// One sweep along g's plane axis in direction dir. Each thread owns the rows [r0, r1) of every
// plane. afterPlane(p, r0, r1) runs on the thread's rows of plane p once they are final: for the
// start plane (which a sweep reads but does not change) before the loop, for every other plane
// right after its rows are swept (still in cache) and before the plane's barrier.
template <class AfterPlane = NoHook>
void sweep(Run& run, const SweepGeometry& g, float* dist, const std::uint8_t* q, int dir, int tid,
           AfterPlane afterPlane = {}) {
  const int r0 = int(std::int64_t(g.rows) * tid / run.threads);
  const int r1 = int(std::int64_t(g.rows) * (tid + 1) / run.threads);
  int changed = 0;
  afterPlane(dir > 0 ? 0 : g.planes - 1, r0, r1);
  // Planes whose rows are not contiguous (x and y sweeps: rows of one plane lie a slice apart)
  // defeat the hardware prefetcher when the sweep runs downwards in memory. There the next
  // plane's rows are fetched into L2 by hand while this plane is swept, and the entering-rule
  // kernel walks rows and voxels downwards (measured at 256³, 2 threads: x− and y− took 14 ms
  // against 6–8 ms for x+ and y+; 9–10 ms with the prefetch; 7 ms walking downwards as well).
  // The z− sweep (contiguous planes) is faster walking upwards: 9.5 ms against 12.5 ms.
  const bool prefetch = dir < 0 && g.rowStride != std::size_t(g.rowLen);
  PlaneArgs pa{};
  pa.rowStride = g.rowStride;
  pa.rows = g.rows;
  pa.r0 = r0;
  pa.r1 = r1;
  pa.n = g.rowLen;
  pa.l = g.lengths;
  pa.base = run.base;
  pa.infRow = run.infRow.data();
  pa.zeroRow = run.zeroRow.data();
  pa.down = prefetch;
  for (int step = 1; step < g.planes; ++step) {
    const int p = dir > 0 ? step : g.planes - 1 - step;
    const int prev = p - dir;
    pa.plane = dist + g.planeStride * p;
    pa.prevPlane = dist + g.planeStride * prev;
    pa.qPlane = q + g.planeStride * p;
    pa.qPrev = q + g.planeStride * prev;
    pa.prefetchAhead = prefetch && step + 1 < g.planes ? -std::ptrdiff_t(g.planeStride) : 0;
    changed |= run.plane(pa);
    afterPlane(p, r0, r1);
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

// Where the current field lives. L1 (run.d) is the result; the x sweeps work on L2 (run.dT).
//  - The first pass starts from L2 built directly from the seeds (initSlice), not from L1.
//  - The z− sweep of a pass that another pass follows writes each finished plane to L2 as well,
//    while it is in cache (measured at 256³: +3 ms on z− against 6–8 ms for a separate transpose).
//  - After x− the field goes back to L1 in a separate transpose of each thread's z slices.
//    Folding that one into x− (blocks of 8 to 64 finished planes) was measured slower: 8-plane
//    blocks took x− from 15 to 25 ms, 64-plane blocks still 19 ms.
// Each thread transposes only its own z slices (x and y sweeps split planes into z rows the same
// way), so the transposes need no extra barriers.
void worker(Run& run, int tid) {
  const Dims d = run.dims;
  const std::size_t nxy = std::size_t(d.x) * d.y;
  const int zs0 = int(std::int64_t(d.z) * tid / run.threads), zs1 = int(std::int64_t(d.z) * (tid + 1) / run.threads);
  const std::uint8_t* q = run.problem.density.data();
  const int planned = run.problem.params.converge ? run.problem.params.maxPasses : run.problem.params.passes;
  {
    // Thread 0 allocates L1 (a vector, so its first touch is a single-threaded value-init) while
    // the others start building L2; slices are handed out one at a time so nobody waits long.
    if (tid == 0) wdt::resizeOnHugePages(run.d, d.count());
    const std::uint8_t* seeds = run.problem.seeds.data();
    for (int z; (z = run.nextSlice.fetch_add(1, std::memory_order_relaxed)) < d.z;)
      initSlice(seeds + nxy * z, q + nxy * z, run.dT.get() + nxy * z, run.qT.get() + nxy * z, d.x, d.y, run.avx2);
  }
  bool l1Valid = false, l2Valid = true;  // the same in every thread: decided by shared state only
  // z− hook: this thread's rows (y) of the finished plane z go to L2.
  const auto toL2 = [&](int z, int r0, int r1) {
    transposeRows(run.d.data() + nxy * z, run.dT.get() + nxy * z, d.x, d.y, r0, r1, run.avx2);
  };
  for (int pass = 0; pass < planned; ++pass) {
    const auto t0 = std::chrono::steady_clock::now();
    run.changedBy[tid] = 0;
    if (checkCancel(run, tid)) {
      if (!l1Valid) {
        transposeSlices(run.dT.get(), run.d.data(), d.y, d.x, zs0, zs1, run.avx2);
        run.barrier.wait();
      }
      break;
    }
    if (!l2Valid) {
      transposeSlices(run.d.data(), run.dT.get(), d.x, d.y, zs0, zs1, run.avx2);
      run.barrier.wait();
    }
    sweep(run, run.x, run.dT.get(), run.qT.get(), +1, tid);
    if (checkCancel(run, tid)) {
      transposeSlices(run.dT.get(), run.d.data(), d.y, d.x, zs0, zs1, run.avx2);  // keep the partial x+ result
      run.barrier.wait();
      break;
    }
    sweep(run, run.x, run.dT.get(), run.qT.get(), -1, tid);
    transposeSlices(run.dT.get(), run.d.data(), d.y, d.x, zs0, zs1, run.avx2);
    l1Valid = true;
    if (checkCancel(run, tid)) break;
    sweep(run, run.y, run.d.data(), q, +1, tid);
    if (checkCancel(run, tid)) break;
    sweep(run, run.y, run.d.data(), q, -1, tid);
    if (checkCancel(run, tid)) break;
    sweep(run, run.z, run.d.data(), q, +1, tid);
    if (checkCancel(run, tid)) break;
    l2Valid = pass + 1 < planned;
    if (l2Valid)
      sweep(run, run.z, run.d.data(), q, -1, tid, toL2);
    else
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

// The x sweeps' scratch arrays (dT, qT) of the most recent size, kept between calls: fresh ones
// cost their page faults and zeroing in every call (80 MB at 256³: 10–12 ms of a 2-pass field's
// ~120 ms, bench/RESULTS.md). One set, of at most kKeptScratchVoxels (80 MB stays allocated; a
// 512³ run's 640 MB does not); a call that finds it taken (another thread's run) or of another size
// allocates its own, and the last call to finish leaves its set here.
constexpr std::size_t kKeptScratchVoxels = std::size_t(256) * 256 * 256;
struct Scratch {
  std::size_t count = 0;
  std::unique_ptr<float[]> dT;
  std::unique_ptr<std::uint8_t[]> qT;
};

std::mutex gScratchMutex;
Scratch gScratch;

Scratch takeScratch(std::size_t count) {
  {
    std::lock_guard<std::mutex> lock(gScratchMutex);
    if (gScratch.count == count && gScratch.dT) return std::exchange(gScratch, Scratch{});
  }
  Scratch s;
  s.count = count;
  s.dT.reset(wdt::newOnHugePages<float>(count));
  s.qT.reset(wdt::newOnHugePages<std::uint8_t>(count));
  return s;
}

void keepScratch(Scratch s) {
  if (s.count > kKeptScratchVoxels) return;  // freed here
  std::lock_guard<std::mutex> lock(gScratchMutex);
  gScratch = std::move(s);
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
  // Threads meet at a barrier after every plane: one thread per 2K voxels of a plane, at most one
  // per core. Measured on 2 cores (bench/RESULTS.md): 2 threads take 0.85 against 1.42 ms per pass
  // at 64³ (4K voxels a plane) and 5.6 against 10.7 at 128³; at 32³ (1K) the two are even.
  const std::size_t planeVoxels = d.count() / std::size_t(std::max({d.x, d.y, d.z}));
  int threads = int(std::min<std::size_t>(std::size_t(hw), std::max<std::size_t>(1, planeVoxels / 2048)));
  // AT_WDT_THREADS=N forces N threads (benchmarks, and tests of the multi-threaded schedule).
  if (const char* env = std::getenv("AT_WDT_THREADS")) threads = std::clamp(std::atoi(env), 1, 256);
  Run run(problem, control, threads);
  run.dims = d;
  run.base = problem.params.baseCost;
  // AT_WDT_NO_AVX2 (any value) takes the baseline (SSE2) code on an AVX2 machine: tests use it.
  run.avx2 = __builtin_cpu_supports("avx2") && !std::getenv("AT_WDT_NO_AVX2");
  run.plane = planeFunction(wdt::costKernel(problem.params), run.avx2);
  Scratch scratch = takeScratch(d.count());
  run.dT = std::move(scratch.dT);
  run.qT = std::move(scratch.qT);
  const int longest = std::max({d.x, d.y, d.z});
  run.infRow.assign(std::size_t(longest), kInf);
  run.zeroRow.assign(std::size_t(longest), 0);
  run.changedBy.assign(std::size_t(threads), 0);

  const float sx = float(grid.spacingMm[0]), sy = float(grid.spacingMm[1]), sz = float(grid.spacingMm[2]);
  // L2 (y contiguous): planes x, rows z.        L1 (x contiguous): y sweep planes y, rows z;
  const std::size_t nxy = std::size_t(d.x) * d.y;
  run.x = {std::size_t(d.y), nxy, d.y, d.z, d.x, wdt::axisSweepLengths(0, sx, sy, sz)};
  run.y = {std::size_t(d.x), nxy, d.x, d.z, d.y, wdt::axisSweepLengths(1, sx, sy, sz)};
  // z sweep planes z, rows y.
  run.z = {nxy, std::size_t(d.x), d.x, d.y, d.z, wdt::axisSweepLengths(2, sx, sy, sz)};

  std::vector<std::thread> team;
  team.reserve(std::size_t(threads - 1));
  for (int t = 1; t < threads; ++t) team.emplace_back([&run, t] { worker(run, t); });
  worker(run, 0);
  for (std::thread& t : team) t.join();
  scratch.dT = std::move(run.dT);
  scratch.qT = std::move(run.qT);
  keepScratch(std::move(scratch));

  WdtResult result;
  result.field.distances.geometry = grid;
  result.field.distances.voxels = std::move(run.d);
  result.field.downsample = problem.params.downsample;
  WdtStats& s = result.stats;
  s.passesRun = run.passesRun;
  s.converged = run.passesRun > 0 && !run.lastChanged && !run.cancelled;
  s.cancelled = run.cancelled;
  s.msPerPass = std::move(run.msPerPass);
  for (double ms : s.msPerPass) s.msCompute += ms;
  s.backendUsed = WdtBackend::Cpu;
  s.device = "CPU (" + std::to_string(threads) + (threads == 1 ? " thread)" : " threads)");
  s.msTotal = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return result;
}

}  // namespace at
