// The built-in dataset: a synthetic temporal-bone phantom. It is not a scan of anyone: shapes are
// analytic (tubes, spirals, ellipsoids, tori) placed at plausible relative positions, with HU in
// realistic ranges and mild seeded noise. Its purpose is to make the paper's effects visible and
// testable: air- and fluid-filled canals near the cochlea are cheaply reachable from it, voxels
// behind thick otic capsule are not; the ossicles sit in air reachable from the tympanic cavity.
//
// Convention: a RIGHT temporal bone in LPS millimetres, identity direction, the cube centred at 0:
// lateral = −x (towards the skin and the external auditory canal), medial = +x (the internal
// auditory canal opens on the medial face), anterior = −y, posterior = +y, superior = +z.
// Anatomy is placed in millimetres, so every size shows the same anatomy (tubes thinner than a
// voxel are widened to 0.9 voxel so that they stay connected on coarse grids).
#pragma once

#include <cstdint>

#include "volume/structure.h"

namespace at {

struct PhantomOptions {
  int size = 256;              // voxels per axis (cube); the physical extent stays fixed
  double extentMm = 51.2;      // edge length of the cube → 0.2 mm voxels at 256
  std::uint64_t seed = 1;
};

// Deterministic: the same options give the same bytes.
Dataset makePhantom(const PhantomOptions& options = {});

// Structure ids of the phantom, in label order (label = index + 1).
const std::vector<Structure>& phantomStructures();

}  // namespace at
