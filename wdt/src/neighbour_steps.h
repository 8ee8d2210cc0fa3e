// The 26 steps of the 26-connected grid, each with its index offset and its physical length
// (stencil.h's stepLength, so every user of the table takes the float the sweeps take).
#pragma once

#include <cstdint>
#include <vector>

#include "volume/geometry.h"
#include "wdt/stencil.h"

namespace at::wdt {

struct NeighbourStep {
  int dx, dy, dz;
  std::int64_t delta;  // index offset of the neighbour in an x-fastest grid of `dims`
  float len;           // mm
};

inline std::vector<NeighbourStep> neighbourSteps(Dims dims, float sx, float sy, float sz) {
  std::vector<NeighbourStep> steps;
  steps.reserve(26);
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx)
        if (dx || dy || dz)
          steps.push_back({dx, dy, dz, dx + std::int64_t(dims.x) * (dy + std::int64_t(dims.y) * dz),
                           stepLength(dx, dy, dz, sx, sy, sz)});
  return steps;
}

}  // namespace at::wdt
