// The whole-volume preset of an unlabelled scan (render/volume_preset.h): its look does not depend
// on the grid's size, down to a µCT finer than 0.1 mm.
#include <doctest/doctest.h>

#include <cmath>

#include "render/render_settings.h"
#include "render/volume_preset.h"

using namespace at;
using namespace at::render;

namespace {

// The opacity a ray gains crossing `lengthMm` of a sample of TF opacity `alpha` (given per
// `refMm`), as the ray caster composites it.
double opacityAcross(double alpha, double refMm, double lengthMm) { return 1.0 - std::pow(1.0 - alpha, lengthMm / refMm); }

}  // namespace

TEST_CASE("WholeVolumePreset_SameVoxelsAtAnyScale_SameOpacityPerVoxel") {
  for (const bool hounsfield : {true, false}) {
    CAPTURE(hounsfield);
    IntensityModel intensity;
    if (!hounsfield) {
      intensity.unit = IntensityUnit::Plain;
      intensity.window = {0, 255};
    }
    Geometry grid;
    grid.dims = {120, 100, 30};
    const auto presetAt = [&](double spacing) {
      grid.spacingMm = {spacing, spacing, spacing};
      return std::pair{wholeVolumePreset(intensity, grid), wholeVolumeRefMm(grid)};
    };
    const auto [reference, referenceRef] = presetAt(0.1);
    CHECK(referenceRef == doctest::Approx(kWholeVolumeRefMm));
    CHECK(presetAt(0.5).second == doctest::Approx(kWholeVolumeRefMm));  // CT and 0.1 mm µCT: unchanged
    for (const double spacing : {0.05, 0.01, 0.001}) {
      CAPTURE(spacing);
      const auto [fine, fineRef] = presetAt(spacing);
      CHECK(fineRef == doctest::Approx(kWholeVolumeRefMm * spacing / 0.1));
      REQUIRE(fine.dataTf.size() == reference.dataTf.size());
      // What one voxel of each TF level adds along a ray: the same at 0.1 mm and finer.
      for (std::size_t i = 0; i < fine.dataTf.size(); ++i) {
        CAPTURE(i);
        CHECK(fine.dataTf[i].x == doctest::Approx(reference.dataTf[i].x));
        CHECK(opacityAcross(fine.dataTf[i].rgba[3], fineRef, spacing) ==
              doctest::Approx(opacityAcross(reference.dataTf[i].rgba[3], referenceRef, 0.1)).epsilon(1e-4));
      }
    }
  }
}
