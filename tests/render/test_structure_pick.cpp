// pickStructure: hollow structures (air or fluid, transparent) are picked through, where pick()
// stops at the opaque wall behind them; a labelled structure the view does not draw (soft tissue
// before bone) gives way to the labelled one the pixel shows behind it.
#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <optional>

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

namespace {

// Layers stacked along z, seen from above: air (z ≥ 6 mm), a 6 mm slab of `slabHu` with label
// `slabLabel` (0 ≤ z < 6), and bone (1500 HU) with label `boneLabel` below (z < 0).
struct LayerScene {
  Volume volume;
  LabelMap labels;
  FloatVolume field;
  LayerScene(std::int16_t slabHu, std::uint16_t slabLabel, std::uint16_t boneLabel) {
    Geometry g;
    g.dims = {40, 40, 40};
    g.spacingMm = {0.5, 0.5, 0.5};
    g.originMm = {-9.75, -9.75, -9.75};
    volume = Volume(g, -1000);
    labels = LabelMap(g, 0);
    field = FloatVolume(g, std::numeric_limits<float>::infinity());
    for (int k = 0; k < 40; ++k)
      for (int j = 0; j < 40; ++j)
        for (int i = 0; i < 40; ++i) {
          const double z = g.indexToPatient({double(i), double(j), double(k)})[2];
          if (z < 0) {
            volume.at(i, j, k) = 1500;
            labels.at(i, j, k) = boneLabel;
          } else if (z < 6) {
            volume.at(i, j, k) = slabHu;
            labels.at(i, j, k) = slabLabel;
          }
        }
  }
};

RenderSettings layerView() {
  RenderSettings s;
  s.width = s.height = 64;
  s.opacityRefMm = 0.25;
  s.camera = Camera::named(NamedView::Superior, {0, 0, 0}, 12);
  return s;
}

}  // namespace

TEST_CASE("pickStructure names what the view shows behind a labelled structure it does not draw") {
  const RenderSettings s = layerView();
  const TransferFunction2D table = shadingTable(s.preset);
  // Tissue the preset does not draw (as a bone preset leaves muscle out) over a labelled bone (a
  // vertebra): the bone is what the pixel shows, so it is what the pointer names, wherever it is.
  std::optional<std::int16_t> undrawn;
  for (std::int16_t hu = 100; hu >= -900 && !undrawn; hu = std::int16_t(hu - 50)) {
    const LayerScene scene(hu, 2, 3);
    const SceneVolumes sv{&scene.volume, &scene.labels, &scene.field, 0};
    const PickPair depths = pickAtTwoThresholds(sv, s, table, 32, 32, kVisibleOpacity, kSeenThroughOpacity);
    if (depths.low.hit && depths.low.pointMm[2] < 0.5) undrawn = hu;
  }
  REQUIRE(undrawn);
  const LayerScene muscleOnVertebra(*undrawn, 2, 3);
  const SceneVolumes sv{&muscleOnVertebra.volume, &muscleOnVertebra.labels, &muscleOnVertebra.field, 0};
  for (double x = 8; x < 56; x += 6)
    for (double y = 8; y < 56; y += 6) {
      CAPTURE(x);
      CAPTURE(y);
      const PickPair depths = pickAtTwoThresholds(sv, s, table, x, y, kVisibleOpacity, kSeenThroughOpacity);
      REQUIRE(depths.low.hit);
      CHECK(depths.low.pointMm[2] < 0.5);  // nothing is drawn before the bone
      const PickResult hit = pickStructure(sv, s, table, x, y);
      CHECK(hit.label == 3);
      CHECK(hit.pointMm[2] < 0.5);
    }
  // Over an unlabelled bone the undrawn structure in front keeps the name: a canal or cavity is
  // seen by its walls (the canal test above).
  const LayerScene muscleOnBone(*undrawn, 2, 0);
  const SceneVolumes bare{&muscleOnBone.volume, &muscleOnBone.labels, &muscleOnBone.field, 0};
  CHECK(pickStructure(bare, s, table, 32, 32).label == 2);
  // A structure the view draws (a bone slab) is named even with another labelled bone behind it.
  const LayerScene boneOnBone(1500, 2, 3);
  const SceneVolumes drawn{&boneOnBone.volume, &boneOnBone.labels, &boneOnBone.field, 0};
  CHECK(pickStructure(drawn, s, table, 32, 32).label == 2);
}

TEST_CASE("pickStructure names a translucent structure the ray shows before an opaque one behind it") {
  RenderSettings s = layerView();
  const TransferFunction2D table = shadingTable(s.preset);
  // Find a slab density the preset draws faintly: the ray shows something inside the slab but
  // turns opaque only in the bone below.
  std::optional<std::int16_t> faint;
  for (std::int16_t hu = 100; hu <= 1500 && !faint; hu = std::int16_t(hu + 50)) {
    const LayerScene scene(hu, 2, 3);
    const SceneVolumes sv{&scene.volume, &scene.labels, &scene.field, 0};
    const PickPair depths = pickAtTwoThresholds(sv, s, table, 32, 32, kVisibleOpacity, kSeenThroughOpacity);
    if (depths.low.hit && depths.low.pointMm[2] >= 0 && depths.high.hit && depths.high.pointMm[2] < 0) faint = hu;
  }
  REQUIRE(faint);
  const LayerScene scene(*faint, 2, 3);
  const SceneVolumes sv{&scene.volume, &scene.labels, &scene.field, 0};
  CHECK(pickStructure(sv, s, table, 32, 32).label == 2);
}
