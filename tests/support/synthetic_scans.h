// Synthetic scans for tests that need data the shared folder lacks: an animal-skull µCT as its
// scanner exports it (uint8 grey values, no HU, no labels). Deterministic for a given seed.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include "volume/grid.h"

namespace at::test {

// The structures of the synthetic µCT, for tests that check segmentations of it.
struct MicroCtLayout {
  Vec3 centre{0, 0, 0};        // voxel coordinates of the skull's centre
  double radius[3]{0, 0, 0};   // outer semi-axes of the skull, voxels
  double shell = 0;            // skull thickness, voxels
  int air = 0, brain = 0, bone = 0, tooth = 0;  // mean grey values
};

inline MicroCtLayout microCtLayout(Dims d) {
  MicroCtLayout m;
  m.centre = {(d.x - 1) / 2.0, (d.y - 1) / 2.0, (d.z - 1) / 2.0};
  m.radius[0] = 0.40 * d.x, m.radius[1] = 0.38 * d.y, m.radius[2] = 0.36 * d.z;
  m.shell = std::max(3.0, 0.08 * std::min({d.x, d.y, d.z}));
  m.air = 14, m.brain = 72, m.bone = 196, m.tooth = 238;
  return m;
}

// Ellipsoid "radius" of voxel (i, j, k): 1 on the skull's outer surface.
inline double microCtRadius(const MicroCtLayout& m, int i, int j, int k, double shrink = 0) {
  const double x = (i - m.centre[0]) / (m.radius[0] - shrink), y = (j - m.centre[1]) / (m.radius[1] - shrink),
               z = (k - m.centre[2]) / (m.radius[2] - shrink);
  return std::sqrt(x * x + y * y + z * z);
}

// An animal-skull µCT: air around a bony ellipsoid shell filled with soft tissue, two dense teeth
// below the skull, Gaussian noise (σ ≈ 5 grey values) and a slight blur of the edges, in 0 … 255 —
// what a µCT scanner's uint8 export looks like (spacing 0.05 mm).
inline FloatVolume syntheticMicroCt(Dims d, std::uint64_t seed = 7) {
  Geometry g;
  g.dims = d;
  g.spacingMm = {0.05, 0.05, 0.05};
  FloatVolume v(g);
  const MicroCtLayout m = microCtLayout(d);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 5.0);
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        const double outer = microCtRadius(m, i, j, k), inner = microCtRadius(m, i, j, k, m.shell);
        // Smooth steps over about one voxel at each surface.
        const double inSkull = std::clamp((1 - outer) * m.radius[0] + 0.5, 0.0, 1.0);
        const double inBrain = std::clamp((1 - inner) * (m.radius[0] - m.shell) + 0.5, 0.0, 1.0);
        double grey = m.air + inSkull * (m.bone - m.air) + inBrain * (m.brain - m.bone);
        for (int t = 0; t < 2; ++t) {
          const double tx = m.centre[0] + (t ? 0.25 : -0.25) * m.radius[0], ty = m.centre[1],
                       tz = m.centre[2] - 1.08 * m.radius[2];
          const double r = std::sqrt((i - tx) * (i - tx) + (j - ty) * (j - ty) + (k - tz) * (k - tz));
          if (r < 0.12 * m.radius[0]) grey = m.tooth;
        }
        v.at(i, j, k) = float(std::clamp(std::round(grey + noise(rng)), 0.0, 255.0));
      }
  return v;
}

}  // namespace at::test
