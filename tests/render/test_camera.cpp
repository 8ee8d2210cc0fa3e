#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "render/camera.h"
#include "render/scene.h"
#include "volume/phantom.h"

using namespace at;
using namespace at::render;

TEST_CASE("Named views look at the target from the named side of the patient (LPS)") {
  const Vec3 target{10, 20, 30};
  const struct {
    const char* name;
    Vec3 eyeSide;
  } views[] = {{"anterior", {0, -1, 0}}, {"posterior", {0, 1, 0}}, {"lateral_left", {1, 0, 0}},
               {"lateral_right", {-1, 0, 0}}, {"superior", {0, 0, 1}}, {"inferior", {0, 0, -1}}};
  for (const auto& v : views) {
    CAPTURE(v.name);
    auto cam = Camera::named(v.name, target, 20);
    REQUIRE(cam);
    const Vec3 toEye = cam->eye() - target;
    CHECK(dot(toEye, v.eyeSide) / norm(toEye) == doctest::Approx(1.0));
    // The target projects to the image centre.
    auto px = cam->project(target, 100, 80);
    REQUIRE(px);
    CHECK((*px)[0] == doctest::Approx(49.5));
    CHECK((*px)[1] == doctest::Approx(39.5));
  }
  CHECK_FALSE(Camera::named("sideways", target, 20));
}

TEST_CASE("Anterior view shows the patient's right on the image's left, superior up") {
  Camera cam = Camera::named(NamedView::Anterior, {0, 0, 0}, 20);
  auto left = cam.project({10, 0, 0}, 100, 100);   // patient left (+x)
  auto up = cam.project({0, 0, 10}, 100, 100);     // superior
  REQUIRE(left);
  REQUIRE(up);
  CHECK((*left)[0] > 49.5);
  CHECK((*up)[1] < 49.5);
}

TEST_CASE("rayThroughPixel and project are inverse to each other") {
  Camera cam = Camera::named(NamedView::LateralLeft, {1, 2, 3}, 30);
  cam.orbit(25, -10);
  cam.zoom(1.3);
  for (double x : {3.0, 50.0, 97.0})
    for (double y : {5.0, 61.0}) {
      const Ray r = cam.rayThroughPixel(x, y, 100, 70);
      auto px = cam.project(r.origin + 40.0 * r.direction, 100, 70);
      REQUIRE(px);
      CHECK((*px)[0] == doctest::Approx(x).epsilon(1e-6));
      CHECK((*px)[1] == doctest::Approx(y).epsilon(1e-6));
    }
}

TEST_CASE("Orbiting keeps the distance to the target; zooming divides it") {
  Camera cam = Camera::named(NamedView::Superior, {5, 5, 5}, 10);
  const double d0 = norm(cam.eye() - cam.target);
  cam.orbit(90, 30);
  CHECK(norm(cam.eye() - cam.target) == doctest::Approx(d0));
  CHECK(dot(cam.forward(), cam.up()) == doctest::Approx(0.0).epsilon(1e-9));
  cam.zoom(2);
  CHECK(norm(cam.eye() - cam.target) == doctest::Approx(d0 / 2));
  const Mat4 vp = cam.viewProjection(1.5);
  const Mat4 id = vp * vp.inverse();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) CHECK(id(r, c) == doctest::Approx(r == c ? 1.0 : 0.0).epsilon(1e-9));
}

TEST_CASE("A clipping plane keeps the side opposite its normal") {
  auto plane = ClipPlane::fromCoefficients(0, 0, 2, 4);  // z <= 2
  REQUIRE(plane);
  CHECK(plane->keeps({0, 0, 1.9}));
  CHECK_FALSE(plane->keeps({0, 0, 2.1}));
  CHECK_FALSE(ClipPlane::fromCoefficients(0, 0, 0, 1));
}

TEST_CASE("A structure's frame read inside a box holding its voxels equals the whole map's; the box it reports is tight") {
  const Dataset ds = makePhantom({64, 51.2, 1});
  const Structure* cochlea = ds.findStructure("cochlea");
  REQUIRE(cochlea);
  auto whole = structureFrame(ds.labels, cochlea->label);
  REQUIRE(whole);
  const std::array<int, 6> b = whole->voxelBox;
  CHECK(b[0] < b[3]);
  // Tight: every face of the box touches a voxel of the structure.
  for (std::size_t a = 0; a < 3; ++a)
    for (int face : {b[a], b[a + 3] - 1}) {
      std::array<int, 6> slab = b;
      slab[a] = face;
      slab[a + 3] = face + 1;
      CHECK(structureFrame(ds.labels, cochlea->label, slab));
    }
  // An edit's box joined with it (here: a box around a corner of the grid) reads fewer voxels and
  // gives the same frame, point for point.
  const std::array<int, 6> joined{std::min(b[0], 0), std::min(b[1], 0), std::min(b[2], 0), b[3], b[4], b[5]};
  auto boxed = structureFrame(ds.labels, cochlea->label, joined);
  REQUIRE(boxed);
  CHECK(boxed->voxelCount == whole->voxelCount);
  CHECK(boxed->voxelBox == whole->voxelBox);
  CHECK(boxed->centroidMm == whole->centroidMm);
  CHECK(boxed->anchorMm == whole->anchorMm);
  CHECK(boxed->radiusMm == whole->radiusMm);
  CHECK(boxed->pointsMm == whole->pointsMm);
  // A box that misses part of it sees less (the caller's contract matters).
  std::array<int, 6> cut = b;
  cut[3] = b[0] + (b[3] - b[0]) / 2;
  auto part = structureFrame(ds.labels, cochlea->label, cut);
  REQUIRE(part);
  CHECK(part->voxelCount < whole->voxelCount);
  // A box without it: the usual error.
  CHECK_FALSE(structureFrame(ds.labels, cochlea->label, {0, 0, 0, 1, 1, 1}));
}
