// pickStructure: hollow structures (air or fluid, transparent) are picked through, where pick()
// stops at the opaque wall behind them.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>

#include "render/structure_pick.h"

using namespace at;
using namespace at::render;

namespace {

// Bone (1500 HU) everywhere but a vertical air canal (label 1, radius 2 mm) drilled from the top
// face (z = +10 mm) down to z = 0, like the external auditory canal seen from outside.
struct CanalScene {
  Volume volume;
  LabelMap labels;
  FloatVolume field;  // +inf: no structure's field (context only)
  CanalScene() {
    Geometry g;
    g.dims = {40, 40, 40};
    g.spacingMm = {0.5, 0.5, 0.5};
    g.originMm = {-9.75, -9.75, -9.75};
    volume = Volume(g, 1500);
    labels = LabelMap(g, 0);
    field = FloatVolume(g, std::numeric_limits<float>::infinity());
    for (int k = 0; k < 40; ++k)
      for (int j = 0; j < 40; ++j)
        for (int i = 0; i < 40; ++i) {
          const Vec3 p = g.indexToPatient({double(i), double(j), double(k)});
          if (p[2] >= 0 && p[0] * p[0] + p[1] * p[1] <= 4.0) {
            volume.at(i, j, k) = -1000;
            labels.at(i, j, k) = 1;
          }
        }
  }
};

}  // namespace

TEST_CASE("pickStructure finds a hollow canal that the opacity pick passes through") {
  const CanalScene scene;
  RenderSettings s;
  s.width = s.height = 64;
  s.opacityRefMm = 0.25;  // the default preset's bone opacity per quarter millimetre: an opaque floor
  s.camera = Camera::named(NamedView::Superior, {0, 0, 0}, 12);
  const SceneVolumes sv{&scene.volume, &scene.labels, &scene.field, 0};
  const TransferFunction2D table = shadingTable(s.preset);

  const auto centre = s.camera.project({0, 0, 5}, s.width, s.height);
  REQUIRE(centre);
  const PickResult opaque = pick(sv, s, table, (*centre)[0], (*centre)[1]);
  REQUIRE(opaque.hit);
  CHECK(opaque.label == 0);               // the canal's bone floor
  CHECK(std::abs(opaque.pointMm[2]) < 1);
  const PickResult canal = pickStructure(sv, s, table, (*centre)[0], (*centre)[1]);
  CHECK(canal.hit);
  CHECK(canal.label == 1);
  CHECK(canal.pointMm[2] > 8);            // met where the ray enters the canal, at the top face

  // Over plain bone 6 mm from the canal: the bone surface, no label.
  const auto bone = s.camera.project({6, 0, 10}, s.width, s.height);
  REQUIRE(bone);
  const PickResult b = pickStructure(sv, s, table, (*bone)[0], (*bone)[1]);
  CHECK(b.hit);
  CHECK(b.label == 0);

  // The clipping plane: labels on its cut side do not count.
  s.clip = ClipPlane{{-1, 0, 0}, 3};  // keeps dot(n, p) <= d, i.e. x >= -3: the canal stays
  CHECK(pickStructure(sv, s, table, (*centre)[0], (*centre)[1]).label == 1);
  s.clip = ClipPlane{{1, 0, 0}, -3};  // keeps x <= -3: the canal (|x| <= 2) is cut away
  CHECK(pickStructure(sv, s, table, (*centre)[0], (*centre)[1]).label == 0);
}
