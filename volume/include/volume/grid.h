// A dense voxel grid: values of type T on a Geometry. Volumes (HU), label maps and distance fields
// are all grids; the CPU grid is the single source of truth, GPU copies derive from it.
#pragma once

#include <cassert>
#include <cstdint>
#include <vector>

#include "volume/geometry.h"

namespace at {

template <class T>
struct Grid {
  Geometry geometry;
  std::vector<T> voxels;  // dims.count() values, i contiguous

  Grid() = default;
  explicit Grid(const Geometry& g, T fill = T{}) : geometry(g), voxels(g.dims.count(), fill) {}

  const Dims& dims() const { return geometry.dims; }
  T& at(int i, int j, int k) {
    assert(geometry.dims.contains(i, j, k) && "Grid::at: index outside the grid");
    return voxels[geometry.dims.index(i, j, k)];
  }
  const T& at(int i, int j, int k) const {
    assert(geometry.dims.contains(i, j, k) && "Grid::at: index outside the grid");
    return voxels[geometry.dims.index(i, j, k)];
  }
  bool empty() const { return voxels.empty(); }
};

// CT intensities in Hounsfield units.
using Volume = Grid<std::int16_t>;
// Float images: NIfTI/NRRD float data, distance fields, resampled intensities.
using FloatVolume = Grid<float>;
// Label values; 0 is background. uint8 label files are widened on load.
using LabelMap = Grid<std::uint16_t>;
// One byte per voxel: non-zero = inside.
using Mask = Grid<std::uint8_t>;

}  // namespace at
