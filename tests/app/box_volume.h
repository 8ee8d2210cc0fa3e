// A bright box in a dark volume on an anisotropic grid (0.8 × 0.8 × 2 mm voxels, plain
// intensities, no labels): what the segment editor's 3-D tests paint on.
#pragma once

#include <filesystem>

#include <doctest/doctest.h>

#include "test_support.h"
#include "volume/nrrd_io.h"

namespace at::test {

constexpr int kBoxLo[3] = {14, 14, 5}, kBoxHi[3] = {34, 34, 15};  // voxel ranges, inclusive

inline std::filesystem::path writeBox(const TempDir& dir) {
  Geometry g;
  g.dims = {48, 48, 20};
  g.spacingMm = {0.8, 0.8, 2.0};
  FloatVolume image(g, 10.0f);
  for (int k = kBoxLo[2]; k <= kBoxHi[2]; ++k)
    for (int j = kBoxLo[1]; j <= kBoxHi[1]; ++j)
      for (int i = kBoxLo[0]; i <= kBoxHi[0]; ++i) image.at(i, j, k) = 220.0f;
  const std::filesystem::path path = dir / "box.nrrd";
  REQUIRE(writeNrrd(path.string(), image, ScalarKind::UInt8));
  return path;
}

}  // namespace at::test
