#include <doctest/doctest.h>

#include <cmath>

#include "render/camera.h"

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
