// The local passes of the CPU growth engine's brick box (growth_brick_box.h): rows relaxed along
// the contiguous axis, written for the auto-vectoriser, one function per cost kernel with an AVX2
// clone.
#include "growth_brick_box.h"

#include <algorithm>

namespace at::growth_cpu {

namespace {

using wdt::CostKernel;
using wdt::SweepLengths;

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

}  // namespace

RelaxBoxFn relaxBoxFunction(CostKernel k, bool avx2) {
  return wdt::withCostKernel(k, [avx2]<CostKernel K>() -> RelaxBoxFn { return avx2 ? &relaxBoxAvx2<K> : &relaxBoxBaseline<K>; });
}

}  // namespace at::growth_cpu
