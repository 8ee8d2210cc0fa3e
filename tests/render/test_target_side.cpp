// render/target_side.h: the side a locate question's view turns to so that its target can be
// clicked — the one choice the terminal's pictures and the desktop's exam share.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "render/scene.h"
#include "render/structure_pick.h"
#include "render/target_side.h"
#include "test_support.h"

using namespace at;
using namespace at::render;

namespace {

const char* kSides[] = {"anterior", "posterior", "lateral_left", "lateral_right", "superior", "inferior"};

// Bone (1500 HU, unlabelled) filling a 20 mm cube, with the target (label 1, an air ball of radius
// 2 mm) at its centre. `openSide`, when given, is the side an air canal runs from the ball to the
// cube's face: the only side from which the target is not behind ≥ 7 mm of bone.
struct BuriedTarget {
  Volume volume;
  LabelMap labels;
  FloatVolume field;
  BuriedTarget(const std::optional<std::string>& openSide) {
    Geometry g;
    g.dims = {40, 40, 40};
    g.spacingMm = {0.5, 0.5, 0.5};
    g.originMm = {-9.75, -9.75, -9.75};
    volume = Volume(g, 1500);
    labels = LabelMap(g, 0);
    field = FloatVolume(g, std::numeric_limits<float>::infinity());
    Vec3 toward{0, 0, 0};
    if (openSide) {
      const Camera c = Camera::named(*parseNamedView(*openSide), {0, 0, 0}, 10);
      toward = -1.0 * c.forward();  // from the ball towards the camera
    }
    for (int k = 0; k < 40; ++k)
      for (int j = 0; j < 40; ++j)
        for (int i = 0; i < 40; ++i) {
          const Vec3 p = g.indexToPatient({double(i), double(j), double(k)});
          if (norm(p) <= 2.0) {
            volume.at(i, j, k) = -1000;
            labels.at(i, j, k) = 1;
          } else if (openSide) {
            const double along = dot(p, toward);
            if (along > 0 && norm(p - along * toward) <= 1.5) volume.at(i, j, k) = -1000;  // the canal
          }
        }
  }
};

// Whether the target of `scene` can be clicked from `side` in a 64 × 64 picture.
bool clickableFrom(const BuriedTarget& scene, const std::string& side) {
  RenderSettings s;
  s.width = s.height = 64;
  s.opacityRefMm = 0.25;  // the default preset's bone opacity per quarter millimetre: opaque
  s.camera = Camera::named(*parseNamedView(side), {0, 0, 0}, 12);
  const SceneVolumes sv{&scene.volume, &scene.labels, &scene.field, 0};
  const TransferFunction2D table = shadingTable(s.preset);
  return targetClickableAt(s.camera, s.width, s.height, scene.labels, 1, s.clip,
                           [&](double x, double y) { return pickStructure(sv, s, table, x, y); });
}

}  // namespace

TEST_CASE("targetSidesToTry: the question's own side first, then every named side once") {
  for (const char* own : kSides) {
    const auto sides = targetSidesToTry(own);
    CHECK(sides.front() == own);
    CHECK(sides.size() == 6);
    CHECK(std::set<std::string>(sides.begin(), sides.end()).size() == 6);
    for (const char* s : kSides) CHECK(std::count(sides.begin(), sides.end(), s) == 1);
  }
  // A side that is not one of the named six (an author's free camera has none) is tried first, then all six.
  const auto sides = targetSidesToTry("oblique");
  CHECK(sides.size() == 7);
  CHECK(sides.front() == "oblique");
}

TEST_CASE("firstSideShowingTarget returns the first side in order that shows the target, and passes errors on") {
  const std::uint64_t seed = test::freshSeed("firstSideShowingTarget");
  std::mt19937_64 rng(seed);
  for (int round = 0; round < 50; ++round) {
    const std::string own = kSides[rng() % 6];
    std::set<std::string> showing;
    for (const char* s : kSides)
      if (rng() % 3 == 0) showing.insert(s);
    std::vector<std::string> asked;
    auto side = firstSideShowingTarget(own, [&](const std::string& s) -> Result<bool> {
      asked.push_back(s);
      return showing.count(s) > 0;
    });
    REQUIRE(side);
    const auto order = targetSidesToTry(own);
    const auto first = std::find_if(order.begin(), order.end(), [&](const std::string& s) { return showing.count(s); });
    if (first == order.end()) {
      CHECK_FALSE(side->has_value());
      CHECK(asked == order);
    } else {
      REQUIRE(side->has_value());
      CHECK(**side == *first);
      CHECK(asked == std::vector<std::string>(order.begin(), first + 1));  // none asked after the first that shows
    }
  }
  auto failed = firstSideShowingTarget("superior", [](const std::string& s) -> Result<bool> {
    if (s == "anterior") return fail("anterior: no camera");
    return false;
  });
  REQUIRE_FALSE(failed);
  CHECK(failed.error().message == "anterior: no camera");
}

TEST_CASE("targetClickableAt: a target buried in bone is clickable only down its open canal") {
  for (const char* open : kSides) {
    CAPTURE(open);
    const BuriedTarget scene{std::string(open)};
    for (const char* side : kSides) {
      CAPTURE(side);
      CHECK(clickableFrom(scene, side) == (std::string(side) == open));
    }
    // From any side the question asks from, the search ends on the open side.
    for (const char* own : kSides) {
      auto chosen = firstSideShowingTarget(own, [&](const std::string& s) -> Result<bool> { return clickableFrom(scene, s); });
      REQUIRE(chosen);
      REQUIRE(chosen->has_value());
      CHECK(**chosen == open);
    }
  }
  // Closed on every side: no side shows it, and the caller keeps its own.
  const BuriedTarget closed(std::nullopt);
  auto chosen = firstSideShowingTarget("superior", [&](const std::string& s) -> Result<bool> { return clickableFrom(closed, s); });
  REQUIRE(chosen);
  CHECK_FALSE(chosen->has_value());
}

TEST_CASE("targetClickableAt: a target outside the picture, behind the eye or cut away by the clip plane is not clickable, whatever the pick says") {
  // One voxel labelled 7 at the grid's centre (the origin), seen from above.
  LabelMap labels;
  labels.geometry.dims = {5, 5, 5};
  labels.geometry.spacingMm = {1, 1, 1};
  labels.geometry.originMm = {-2, -2, -2};
  labels.voxels.assign(labels.geometry.dims.count(), 0);
  labels.voxels[labels.geometry.dims.index(2, 2, 2)] = 7;
  REQUIRE(labels.geometry.indexToPatient({2, 2, 2}) == Vec3{0, 0, 0});
  const Camera camera = Camera::named(NamedView::Superior, {0, 0, 0}, 10);
  std::vector<std::array<double, 2>> clicked;
  const auto hitsTarget = [&](double x, double y) {
    clicked.push_back({x, y});
    return PickResult{true, 7, {0, 0, 0}, 1};
  };
  const auto hitsOther = [](double, double) { return PickResult{true, 3, {0, 0, 0}, 1}; };
  const auto misses = [](double, double) { return PickResult{}; };
  CHECK(targetClickableAt(camera, 64, 64, labels, 7, std::nullopt, hitsTarget));
  REQUIRE(clicked.size() == 1);
  const auto centre = camera.project({0, 0, 0}, 64, 64);
  REQUIRE(centre);
  CHECK(std::hypot(clicked[0][0] - (*centre)[0], clicked[0][1] - (*centre)[1]) <= 3.0);  // where it lies (grid of every 2nd pixel)
  CHECK_FALSE(targetClickableAt(camera, 64, 64, labels, 7, std::nullopt, hitsOther));
  CHECK_FALSE(targetClickableAt(camera, 64, 64, labels, 7, std::nullopt, misses));
  CHECK_FALSE(targetClickableAt(camera, 64, 64, labels, 5, std::nullopt, hitsTarget));  // no voxel of label 5
  const Camera aside = Camera::named(NamedView::Superior, {500, 0, 0}, 10);  // far outside the view
  CHECK_FALSE(targetClickableAt(aside, 64, 64, labels, 7, std::nullopt, hitsTarget));
  // From below, looking up at a point 50 mm above it: the voxel lies behind the eye.
  const Camera past = Camera::named(NamedView::Inferior, {0, 0, 50}, 1);
  REQUIRE(dot(Vec3{0, 0, 0} - past.eye(), past.forward()) < 0);
  CHECK_FALSE(targetClickableAt(past, 64, 64, labels, 7, std::nullopt, hitsTarget));
  CHECK_FALSE(targetClickableAt(camera, 64, 64, labels, 7, ClipPlane{{0, 0, 1}, -0.5}, hitsTarget));  // cut away
  CHECK(targetClickableAt(camera, 64, 64, labels, 7, ClipPlane{{0, 0, 1}, 0.5}, hitsTarget));          // kept
}
