// Empty-space skipping for the ray caster: which blocks of kBlockVoxels³ voxels may hold a sample
// that draws something. A block is empty for the context when no HU its samples can take (with the
// linear filter) meets a table entry of non-zero opacity at the distances its samples can take, or
// when its edges are all weaker than the surface threshold; it is "near the structure" when the
// selected label lies in it or a neighbour (the smoothed mask reaches one voxel out). Rays jump
// over blocks that are neither, so skipping keeps the image.
#pragma once

#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "render/gradient_volume.h"
#include "render/transfer_function.h"
#include "volume/grid.h"

namespace at::render::gl {

constexpr int kBlockVoxels = 4;

// Occupancy texel: bit 0 the context may draw in the block, bit 1 the structure's mask reaches
// it; an empty block (neither) holds in bits 2..7 its Chebyshev distance in blocks to the nearest
// non-empty one (1..kMaxLeapBlocks, the largest also meaning farther), so a ray may leap over the
// whole cube of empty blocks around it.
constexpr std::uint8_t kOccupiedContext = 1, kOccupiedStructure = 2;
constexpr int kMaxLeapBlocks = 15;

// Per block, computed once per volume. HU range and edge strength cover the 27 neighbouring
// blocks (a sample in a block interpolates voxels of the next one); labels are the block's own.
struct BlockSummary {
  Dims blocks;
  std::vector<std::int16_t> huMin, huMax;
  std::vector<float> strengthMax;                  // HU per voxel
  std::vector<std::vector<std::uint16_t>> labels;  // sorted
  // The inverse of `labels`: per label, the blocks holding it (ascending indices), so that a
  // selection change touches only the selected structure's blocks.
  std::unordered_map<std::uint16_t, std::vector<std::uint32_t>> blocksOfLabel;

  std::size_t index(int i, int j, int k) const { return blocks.index(i, j, k); }
};

BlockSummary summariseBlocks(const Volume& volume, const LabelMap& labels, const GradientVolume& gradients);
// The labels of the blocks that meet the voxel box {x0, y0, z0, x1, y1, z1} (min inclusive, max
// exclusive) read again from `labels` (an edit changed voxels there), blocksOfLabel with them.
void updateBlockLabels(BlockSummary& b, const LabelMap& labels, const std::array<int, 6>& box);

// The smallest distance per block of kBlockVoxels³ voxels of a field on its own grid, built slice
// by slice (a field uploaded in steps) or at once.
class FieldBlockMinima {
 public:
  void reset(const Geometry& fieldGrid);
  void addSlice(const float* slice, int z);  // dims.x · dims.y values of slice z
  void addAll(const FloatVolume& field);
  bool valid() const { return !minima_.empty(); }
  // The smallest distance any trilinear sample inside the field-index box [lo, hi] can read.
  float minInIndexBox(const Vec3& lo, const Vec3& hi) const;
  const Geometry& grid() const { return grid_; }

 private:
  Geometry grid_;
  Dims blocks_;
  std::vector<float> minima_;
};

// What the context of one table can draw, for occupancy questions in O(1).
class TableVisibility {
 public:
  TableVisibility() = default;
  explicit TableVisibility(const TransferFunction2D& table);  // opacities as uploaded
  // Whether some entry with data column in [c0, c1] and distance row in [0, r1] is visible.
  bool anyVisible(int c0, int c1, int r1) const;
  // The HU range outside which every lookup is zero at every distance ({+big, −big} when none).
  std::array<float, 2> visibleHu() const { return visibleHu_; }
  int columnOf(double hu, bool roundUp) const;
  int rowOf(double normalisedDistance) const;  // the highest row a lookup at n may read

 private:
  int dataSize_ = 0, distanceSize_ = 0;
  double dataMin_ = 0, dataMax_ = 1;
  std::vector<int> prefix_;  // (dataSize+1) × (distanceSize+1) counts of visible entries
  std::array<float, 2> visibleHu_{1e30f, -1e30f};
};

struct OccupancyInputs {
  const BlockSummary* blocks = nullptr;
  const Geometry* volumeGrid = nullptr;
  const TableVisibility* table = nullptr;  // null: no context drawn (bare mode)
  float surfaceLo = 0;                     // edge strength below which the context is invisible …
  bool surfaceFloor = false;               // … unless homogeneous regions keep some opacity
  const FieldBlockMinima* field = nullptr; // null or invalid: every distance possible
  float log2Alpha = 1;                     // distance normalisation: n = 2 / (1 + 2^(d·log2Alpha/unit))
  float distanceUnit = 1;
  float distanceOffset = 0;                // d' = max(0, d − offset) before the unit (render_settings.h)
  std::uint16_t selected = 0;
};

std::vector<std::uint8_t> computeOccupancy(const OccupancyInputs& in);
// The context bit of computeOccupancy for the blocks of z-layers [kLo, kHi) of `occupancy` (the
// grid's size; other layers untouched), so that a grid can be computed a few layers at a time.
void computeContextLayers(const OccupancyInputs& in, int kLo, int kHi, std::vector<std::uint8_t>& occupancy);

// Writes the leap distances into the empty blocks of an occupancy grid (see kMaxLeapBlocks).
void addLeapDistances(const Dims& blocks, std::vector<std::uint8_t>& occupancy);

// The grid for `selected` from the grid of the same inputs with no structure (selected = 0, leap
// distances added): sets the structure bit around the label's blocks and lowers the leap
// distances within kMaxLeapBlocks of them. Equal to computeOccupancy + addLeapDistances with
// `selected`, at a cost that grows with the structure's size, not the volume's (a hover changes
// only the selection).
std::vector<std::uint8_t> withStructure(const BlockSummary& blocks, std::vector<std::uint8_t> contextWithLeaps,
                                        std::uint16_t selected);

}  // namespace at::render::gl
