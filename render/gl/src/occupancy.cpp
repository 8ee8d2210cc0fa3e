#include "occupancy.h"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cmath>
#include <limits>

namespace at::render::gl {

namespace {

// Max/min over the 27 neighbouring blocks of a per-block quantity.
template <class T, class Pick>
std::vector<T> neighbourhood(const Dims& nb, const std::vector<T>& own, T init, Pick pick) {
  std::vector<T> out(own.size());
  for (int k = 0; k < nb.z; ++k)
    for (int j = 0; j < nb.y; ++j)
      for (int i = 0; i < nb.x; ++i) {
        T v = init;
        for (int dk = std::max(k - 1, 0); dk <= std::min(k + 1, nb.z - 1); ++dk)
          for (int dj = std::max(j - 1, 0); dj <= std::min(j + 1, nb.y - 1); ++dj)
            for (int di = std::max(i - 1, 0); di <= std::min(i + 1, nb.x - 1); ++di)
              v = pick(v, own[nb.index(di, dj, dk)]);
        out[nb.index(i, j, k)] = v;
      }
  return out;
}

void indexBlocksOfLabel(BlockSummary& b) {
  b.blocksOfLabel.clear();
  for (std::size_t bi = 0; bi < b.labels.size(); ++bi)
    for (std::uint16_t l : b.labels[bi]) b.blocksOfLabel[l].push_back(std::uint32_t(bi));
}

}  // namespace

BlockSummary summariseBlocks(const Volume& volume, const LabelMap& labels, const GradientVolume& gradients) {
  const Dims& d = volume.dims();
  BlockSummary b;
  b.blocks = {(d.x + kBlockVoxels - 1) / kBlockVoxels, (d.y + kBlockVoxels - 1) / kBlockVoxels,
              (d.z + kBlockVoxels - 1) / kBlockVoxels};
  const std::size_t n = b.blocks.count();
  std::vector<std::int16_t> ownMin(n, std::numeric_limits<std::int16_t>::max());
  std::vector<std::int16_t> ownMax(n, std::numeric_limits<std::int16_t>::min());
  std::vector<float> ownStrength(n, 0.0f);
  b.labels.assign(n, {});
  const bool hasLabels = !labels.empty();
  const bool hasGradients = !gradients.empty();
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j) {
      const std::size_t row = d.index(0, j, k);
      const std::size_t blockRow = b.index(0, j / kBlockVoxels, k / kBlockVoxels);
      std::size_t lastBlock = n;
      std::uint16_t lastLabel = 0;
      for (int i = 0; i < d.x; ++i) {
        const std::size_t bi = blockRow + std::size_t(i / kBlockVoxels);
        const std::int16_t v = volume.voxels[row + std::size_t(i)];
        ownMin[bi] = std::min(ownMin[bi], v);
        ownMax[bi] = std::max(ownMax[bi], v);
        if (hasGradients) ownStrength[bi] = std::max(ownStrength[bi], gradients.strengthAt(row + std::size_t(i)));
        if (!hasLabels) continue;
        const std::uint16_t l = labels.voxels[row + std::size_t(i)];
        if (l == 0 || (bi == lastBlock && l == lastLabel)) continue;
        lastBlock = bi;
        lastLabel = l;
        auto& set = b.labels[bi];
        const auto at = std::lower_bound(set.begin(), set.end(), l);
        if (at == set.end() || *at != l) set.insert(at, l);
      }
    }
  indexBlocksOfLabel(b);
  b.huMin = neighbourhood<std::int16_t>(b.blocks, ownMin, std::numeric_limits<std::int16_t>::max(),
                                        [](std::int16_t a, std::int16_t c) { return std::min(a, c); });
  b.huMax = neighbourhood<std::int16_t>(b.blocks, ownMax, std::numeric_limits<std::int16_t>::min(),
                                        [](std::int16_t a, std::int16_t c) { return std::max(a, c); });
  b.strengthMax = neighbourhood<float>(b.blocks, ownStrength, 0.0f, [](float a, float c) { return std::max(a, c); });
  if (!hasGradients) b.strengthMax.assign(n, std::numeric_limits<float>::max());
  return b;
}

void updateBlockLabels(BlockSummary& b, const LabelMap& labels, const std::array<int, 6>& box) {
  const Dims& d = labels.dims();
  const int lo[3] = {std::max(0, box[0]) / kBlockVoxels, std::max(0, box[1]) / kBlockVoxels, std::max(0, box[2]) / kBlockVoxels};
  const int hi[3] = {(std::min(d.x, box[3]) + kBlockVoxels - 1) / kBlockVoxels,
                     (std::min(d.y, box[4]) + kBlockVoxels - 1) / kBlockVoxels,
                     (std::min(d.z, box[5]) + kBlockVoxels - 1) / kBlockVoxels};
  for (int bk = lo[2]; bk < hi[2]; ++bk)
    for (int bj = lo[1]; bj < hi[1]; ++bj)
      for (int bi = lo[0]; bi < hi[0]; ++bi) {
        std::vector<std::uint16_t>& set = b.labels[b.index(bi, bj, bk)];
        set.clear();
        for (int k = bk * kBlockVoxels, ke = std::min(d.z, k + kBlockVoxels); k < ke; ++k)
          for (int j = bj * kBlockVoxels, je = std::min(d.y, j + kBlockVoxels); j < je; ++j)
            for (int i = bi * kBlockVoxels, ie = std::min(d.x, i + kBlockVoxels); i < ie; ++i)
              if (const std::uint16_t l = labels.voxels[d.index(i, j, k)]; l != 0) set.push_back(l);
        std::sort(set.begin(), set.end());
        set.erase(std::unique(set.begin(), set.end()), set.end());
      }
  indexBlocksOfLabel(b);
}

void FieldBlockMinima::reset(const Geometry& fieldGrid) {
  grid_ = fieldGrid;
  const Dims& d = fieldGrid.dims;
  blocks_ = {(d.x + kBlockVoxels - 1) / kBlockVoxels, (d.y + kBlockVoxels - 1) / kBlockVoxels,
             (d.z + kBlockVoxels - 1) / kBlockVoxels};
  minima_.assign(blocks_.count(), std::numeric_limits<float>::infinity());
}

void FieldBlockMinima::addSlice(const float* slice, int z) {
  const Dims& d = grid_.dims;
  const std::size_t blockRow0 = blocks_.index(0, 0, z / kBlockVoxels);
  for (int j = 0; j < d.y; ++j) {
    const std::size_t blockRow = blockRow0 + std::size_t(j / kBlockVoxels) * std::size_t(blocks_.x);
    const float* row = slice + std::size_t(j) * std::size_t(d.x);
    for (int bi = 0; bi < blocks_.x; ++bi) {
      float m = minima_[blockRow + std::size_t(bi)];
      for (int i = bi * kBlockVoxels, e = std::min(d.x, i + kBlockVoxels); i < e; ++i) m = std::min(m, row[i]);
      minima_[blockRow + std::size_t(bi)] = m;
    }
  }
}

void FieldBlockMinima::addAll(const FloatVolume& field) {
  reset(field.geometry);
  const std::size_t slice = std::size_t(field.dims().x) * std::size_t(field.dims().y);
  for (int z = 0; z < field.dims().z; ++z) addSlice(field.voxels.data() + slice * std::size_t(z), z);
}

float FieldBlockMinima::minInIndexBox(const Vec3& lo, const Vec3& hi) const {
  const int dims[3] = {grid_.dims.x, grid_.dims.y, grid_.dims.z};
  const int nb[3] = {blocks_.x, blocks_.y, blocks_.z};
  int b0[3], b1[3];
  for (int a = 0; a < 3; ++a) {
    const int i0 = std::clamp(int(std::floor(lo[std::size_t(a)])), 0, dims[a] - 1);
    const int i1 = std::clamp(int(std::floor(hi[std::size_t(a)])) + 1, 0, dims[a] - 1);
    b0[a] = std::min(i0 / kBlockVoxels, nb[a] - 1);
    b1[a] = std::min(i1 / kBlockVoxels, nb[a] - 1);
  }
  float m = std::numeric_limits<float>::infinity();
  for (int k = b0[2]; k <= b1[2]; ++k)
    for (int j = b0[1]; j <= b1[1]; ++j)
      for (int i = b0[0]; i <= b1[0]; ++i) m = std::min(m, minima_[blocks_.index(i, j, k)]);
  return m;
}

TableVisibility::TableVisibility(const TransferFunction2D& table)
    : dataSize_(table.dataSize), distanceSize_(table.distanceSize), dataMin_(table.dataMin), dataMax_(table.dataMax) {
  const std::size_t w = std::size_t(dataSize_) + 1;
  prefix_.assign(w * (std::size_t(distanceSize_) + 1), 0);
  int first = -1, last = -1;
  for (int r = 0; r < distanceSize_; ++r)
    for (int c = 0; c < dataSize_; ++c) {
      const int visible = table.value(c, r)[3] > 0.0f ? 1 : 0;
      if (visible) {
        first = first < 0 ? c : std::min(first, c);
        last = std::max(last, c);
      }
      prefix_[std::size_t(r + 1) * w + std::size_t(c + 1)] = visible + prefix_[std::size_t(r) * w + std::size_t(c + 1)] +
                                                             prefix_[std::size_t(r + 1) * w + std::size_t(c)] -
                                                             prefix_[std::size_t(r) * w + std::size_t(c)];
    }
  // The linear filter reads columns floor(c) and floor(c) + 1 at column coordinate
  // c = (hu − dataMin) / span · (size − 1): a sample at or before the centre of the column preceding
  // the first visible one (or at or after the one following the last) reads only invisible columns.
  // A hundredth of a column of margin keeps the test on the safe side of float rounding.
  if (first >= 0) {
    const double perColumn = (dataMax_ - dataMin_) / double(dataSize_ - 1);
    visibleHu_[0] = first == 0 ? -1e30f : float(dataMin_ + (first - 1 - 0.01) * perColumn);
    visibleHu_[1] = last == dataSize_ - 1 ? 1e30f : float(dataMin_ + (last + 1 + 0.01) * perColumn);
  }
}

bool TableVisibility::anyVisible(int c0, int c1, int r1) const {
  if (prefix_.empty()) return false;
  c0 = std::clamp(c0, 0, dataSize_ - 1);
  c1 = std::clamp(c1, 0, dataSize_ - 1);
  r1 = std::clamp(r1, 0, distanceSize_ - 1);
  if (c1 < c0) return false;
  const std::size_t w = std::size_t(dataSize_) + 1;
  const int count = prefix_[std::size_t(r1 + 1) * w + std::size_t(c1 + 1)] - prefix_[std::size_t(c1 + 1)] -
                    prefix_[std::size_t(r1 + 1) * w + std::size_t(c0)] + prefix_[std::size_t(c0)];
  return count > 0;
}

int TableVisibility::columnOf(double hu, bool roundUp) const {
  const double c = std::clamp((hu - dataMin_) / (dataMax_ - dataMin_), 0.0, 1.0) * double(dataSize_ - 1);
  return roundUp ? int(std::ceil(c)) : int(std::floor(c));
}

int TableVisibility::rowOf(double n) const {
  return std::min(distanceSize_ - 1, int(std::ceil(std::clamp(n, 0.0, 1.0) * double(distanceSize_ - 1))) + 1);
}

std::vector<std::uint8_t> computeOccupancy(const OccupancyInputs& in) {
  const BlockSummary& b = *in.blocks;
  const Dims& nb = b.blocks;
  std::vector<std::uint8_t> occ(nb.count(), 0);
  // Structure: the label in the block or a neighbour.
  if (in.selected != 0) {
    std::vector<std::uint8_t> own(nb.count(), 0);
    for (std::size_t i = 0; i < own.size(); ++i)
      own[i] = std::binary_search(b.labels[i].begin(), b.labels[i].end(), in.selected) ? 1 : 0;
    const auto near = neighbourhood<std::uint8_t>(nb, own, 0, [](std::uint8_t a, std::uint8_t c) { return std::max(a, c); });
    for (std::size_t i = 0; i < occ.size(); ++i)
      if (near[i]) occ[i] |= kOccupiedStructure;
  }
  computeContextLayers(in, 0, nb.z, occ);
  return occ;
}

void computeContextLayers(const OccupancyInputs& in, int kLo, int kHi, std::vector<std::uint8_t>& occ) {
  if (!in.table) return;
  const BlockSummary& b = *in.blocks;
  const Dims& nb = b.blocks;
  const bool useField = in.field && in.field->valid() && in.volumeGrid;
  // Volume index → field index is affine: a block's index box maps to the box around its mapped
  // centre with half-extents |linear part| · half-extents.
  Vec3 origin{0, 0, 0};
  Vec3 columns[3];
  if (useField) {
    const Geometry& fg = in.field->grid();
    origin = fg.patientToIndex(in.volumeGrid->indexToPatient({0, 0, 0}));
    for (int a = 0; a < 3; ++a) {
      Vec3 unit{0, 0, 0};
      unit[std::size_t(a)] = 1;
      columns[a] = fg.patientToIndex(in.volumeGrid->indexToPatient(unit)) - origin;
    }
  }
  const double half = 0.5 * (kBlockVoxels + 1);  // the block's voxels and the next one on each side
  for (int k = std::max(kLo, 0); k < std::min(kHi, nb.z); ++k)
    for (int j = 0; j < nb.y; ++j)
      for (int i = 0; i < nb.x; ++i) {
        const std::size_t bi = b.index(i, j, k);
        if (b.huMin[bi] > b.huMax[bi]) continue;
        if (!in.surfaceFloor && b.strengthMax[bi] < in.surfaceLo) continue;
        const int c0 = in.table->columnOf(b.huMin[bi], false), c1 = in.table->columnOf(b.huMax[bi], true);
        int r1 = in.table->rowOf(1.0);
        if (!in.table->anyVisible(c0, c1, r1)) continue;
        if (useField) {
          const double centre[3] = {(i + 0.5) * kBlockVoxels - 0.5, (j + 0.5) * kBlockVoxels - 0.5,
                                    (k + 0.5) * kBlockVoxels - 0.5};
          Vec3 c = origin, extent{0, 0, 0};
          for (int a = 0; a < 3; ++a) {
            c = c + centre[a] * columns[a];
            for (int r = 0; r < 3; ++r) extent[std::size_t(r)] += std::fabs(columns[a][std::size_t(r)]) * (half + 0.5);
          }
          const float dMin = in.field->minInIndexBox(c - extent, c + extent);
          const double x = std::max(0.0, double(dMin) - double(in.distanceOffset)) * double(in.log2Alpha) / double(in.distanceUnit);
          const double nMax = std::isfinite(dMin) ? 2.0 / (1.0 + std::exp2(std::min(x, 126.0))) : 0.0;
          r1 = in.table->rowOf(nMax);
        }
        if (in.table->anyVisible(c0, c1, r1)) occ[bi] |= kOccupiedContext;
      }
}

namespace {

// Blocks [lo, hi) of the block grid, per axis.
struct BlockBox {
  int lo[3], hi[3];
  int size(int a) const { return hi[a] - lo[a]; }
  std::size_t count() const { return std::size_t(size(0)) * std::size_t(size(1)) * std::size_t(size(2)); }
  std::size_t local(int i, int j, int k) const {
    return (std::size_t(k - lo[2]) * std::size_t(size(1)) + std::size_t(j - lo[1])) * std::size_t(size(0)) +
           std::size_t(i - lo[0]);
  }
};

// Chebyshev distance in blocks, capped at kMaxLeapBlocks, from every block of `box` to the nearest
// block of `box` that `occupied(global index)` holds; box-local order. The Chebyshev distance is
// the length of the shortest path through 26-connected neighbours, so two raster passes give it
// exactly (Rosenfeld and Pfaltz's chamfer transform with unit weights): forwards, each block
// takes one more than the least of its 13 neighbours already passed; backwards, the other 13.
// The box is padded by a block of kFar on every side, so the passes need no bounds tests. (The
// previous separable form took O(kMaxLeapBlocks) per block and axis: 25–70 ms for a 64³ grid on
// the 2-core machine, in the frame that changed the field or the selection.)
template <class Occupied>
std::vector<int> cappedChebyshev(const Dims& nb, const BlockBox& box, Occupied occupied) {
  constexpr std::uint8_t kFar = kMaxLeapBlocks;
  const int sx = box.size(0), sy = box.size(1), sz = box.size(2);
  const std::ptrdiff_t px = sx + 2, pxy = px * (sy + 2);
  std::vector<std::uint8_t> d(std::size_t(pxy * (sz + 2)), kFar);
  const auto at = [&](int i, int j, int k) { return std::ptrdiff_t(k + 1) * pxy + std::ptrdiff_t(j + 1) * px + (i + 1); };
  for (int k = 0; k < sz; ++k)
    for (int j = 0; j < sy; ++j)
      for (int i = 0; i < sx; ++i)
        if (occupied(nb.index(box.lo[0] + i, box.lo[1] + j, box.lo[2] + k))) d[std::size_t(at(i, j, k))] = 0;
  // The 13 neighbours before a block in raster order (x fastest), as offsets in the padded box.
  std::array<std::ptrdiff_t, 13> before{};
  int n = 0;
  for (int dk = -1; dk <= 0; ++dk)
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di)
        if (dk < 0 || dj < 0 || (dj == 0 && di < 0)) before[std::size_t(n++)] = dk * pxy + dj * px + di;
  std::uint8_t* v = d.data();
  for (int k = 0; k < sz; ++k)
    for (int j = 0; j < sy; ++j) {
      std::uint8_t* row = v + at(0, j, k);
      for (int i = 0; i < sx; ++i) {
        std::uint8_t best = row[i];
        if (best == 0) continue;
        for (std::ptrdiff_t o : before) best = std::min<std::uint8_t>(best, std::uint8_t(row[std::ptrdiff_t(i) + o] + 1));
        row[i] = std::min(best, kFar);
      }
    }
  for (int k = sz - 1; k >= 0; --k)
    for (int j = sy - 1; j >= 0; --j) {
      std::uint8_t* row = v + at(0, j, k);
      for (int i = sx - 1; i >= 0; --i) {
        std::uint8_t best = row[i];
        if (best <= 1) continue;
        for (std::ptrdiff_t o : before) best = std::min<std::uint8_t>(best, std::uint8_t(row[std::ptrdiff_t(i) - o] + 1));
        row[i] = best;
      }
    }
  std::vector<int> out(box.count());
  for (int k = 0; k < sz; ++k)
    for (int j = 0; j < sy; ++j)
      for (int i = 0; i < sx; ++i) out[box.local(box.lo[0] + i, box.lo[1] + j, box.lo[2] + k)] = d[std::size_t(at(i, j, k))];
  return out;
}

}  // namespace

void addLeapDistances(const Dims& nb, std::vector<std::uint8_t>& occ) {
  const BlockBox all{{0, 0, 0}, {nb.x, nb.y, nb.z}};
  const std::vector<int> d = cappedChebyshev(nb, all, [&](std::size_t b) { return (occ[b] & 3) != 0; });
  for (std::size_t b = 0; b < occ.size(); ++b)
    if (!(occ[b] & 3)) occ[b] = std::uint8_t(std::clamp(d[b], 1, kMaxLeapBlocks) << 2);
}

std::vector<std::uint8_t> withStructure(const BlockSummary& b, std::vector<std::uint8_t> occ, std::uint16_t selected) {
  const auto found = selected != 0 ? b.blocksOfLabel.find(selected) : b.blocksOfLabel.end();
  if (found == b.blocksOfLabel.end() || found->second.empty()) return occ;
  const Dims& nb = b.blocks;
  // The structure bit: the label's blocks and their 26 neighbours (as computeOccupancy).
  BlockBox near{{nb.x, nb.y, nb.z}, {0, 0, 0}};
  for (std::uint32_t own : found->second) {
    const int i = int(own % std::uint32_t(nb.x)), j = int(own / std::uint32_t(nb.x) % std::uint32_t(nb.y)),
              k = int(own / (std::uint32_t(nb.x) * std::uint32_t(nb.y)));
    for (int dk = std::max(k - 1, 0); dk <= std::min(k + 1, nb.z - 1); ++dk)
      for (int dj = std::max(j - 1, 0); dj <= std::min(j + 1, nb.y - 1); ++dj)
        for (int di = std::max(i - 1, 0); di <= std::min(i + 1, nb.x - 1); ++di) {
          const std::size_t bi = nb.index(di, dj, dk);
          if (occ[bi] & kOccupiedStructure) continue;
          // An empty block's leap bits go: it is occupied now.
          occ[bi] = std::uint8_t((occ[bi] & kOccupiedContext) | kOccupiedStructure);
          const int c[3] = {di, dj, dk};
          for (int a = 0; a < 3; ++a) {
            near.lo[a] = std::min(near.lo[a], c[a]);
            near.hi[a] = std::max(near.hi[a], c[a] + 1);
          }
        }
  }
  // Leaps can only shorten within kMaxLeapBlocks of the structure's blocks.
  const int limits[3] = {nb.x, nb.y, nb.z};
  BlockBox reach = near;
  for (int a = 0; a < 3; ++a) {
    reach.lo[a] = std::max(0, near.lo[a] - kMaxLeapBlocks);
    reach.hi[a] = std::min(limits[a], near.hi[a] + kMaxLeapBlocks);
  }
  const std::vector<int> d =
      cappedChebyshev(nb, reach, [&](std::size_t bi) { return (occ[bi] & kOccupiedStructure) != 0; });
  for (int k = reach.lo[2]; k < reach.hi[2]; ++k)
    for (int j = reach.lo[1]; j < reach.hi[1]; ++j)
      for (int i = reach.lo[0]; i < reach.hi[0]; ++i) {
        std::uint8_t& v = occ[nb.index(i, j, k)];
        if (v & 3) continue;
        const int leap = std::min(int(v >> 2), d[reach.local(i, j, k)]);
        v = std::uint8_t(std::clamp(leap, 1, kMaxLeapBlocks) << 2);
      }
  return occ;
}

}  // namespace at::render::gl
