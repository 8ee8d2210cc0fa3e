// Small analytic scenes for the semantic render tests (0.5 mm voxels, centred at the origin).
//
// Chambers (48³, anterior view: patient left (+x) on the image's right):
//
//      soft tissue (40 HU) everywhere
//      N− fluid (label 3)     S fluid (label 1)   |bone|   N+ fluid (label 2)
//        at x = −7              at x = 0           x∈[3,5]    at x = +7          (radius 2 mm)
//
//   Euclidean distances from S to N− and N+ are equal; only the bone wall tells them apart.
//
// Surface (40³): bone (1500 HU) below z = 0, soft tissue (40 HU) above, like the temporalis over the
// temporal bone; S = a bone disk of radius 1.5 mm on the
// surface at the origin (label 1), viewed from superior.
#pragma once

#include "volume/structure.h"

namespace at::test {

struct Scene {
  Dataset dataset;
  FloatVolume weighted;    // WDT from label 1, density weights
  FloatVolume uniform;     // WDT from label 1, uniform weights
};

const Scene& chambersScene();
const Scene& surfaceScene();

}  // namespace at::test
