#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>

#include "render/gl/egl_context.h"
#include "render/gl/volume_renderer.h"
#include "render_fixture.h"

using namespace at;
using namespace at::render;

TEST_CASE("The ray caster draws an analytic sphere where it projects and nothing in the corners") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  // 40³ grid of air with a fluid sphere (label 1) of radius 4 mm inside a bone shell.
  Geometry g;
  g.dims = {40, 40, 40};
  g.spacingMm = {0.5, 0.5, 0.5};
  g.originMm = {-9.75, -9.75, -9.75};
  Volume vol(g, -1000);
  LabelMap labels(g, 0);
  FloatVolume field(g, 0.0f);
  for (int k = 0; k < 40; ++k)
    for (int j = 0; j < 40; ++j)
      for (int i = 0; i < 40; ++i) {
        const Vec3 p = g.indexToPatient({double(i), double(j), double(k)});
        const double r = norm(p);
        if (r <= 4) {
          vol.at(i, j, k) = 10;
          labels.at(i, j, k) = 1;
        } else if (r <= 6) {
          vol.at(i, j, k) = 1500;
        }
        field.at(i, j, k) = float(std::max(0.0, r - 4));
      }
  REQUIRE(gl->setVolume(vol, labels));
  REQUIRE(gl->setField(field));
  gl->setSelected(1);
  RenderSettings s;
  s.width = s.height = 64;
  s.preset.mode = RenderMode::Bare;
  s.camera = Camera::named(NamedView::Anterior, {0, 0, 0}, 10);
  auto img = gl->render(s);
  REQUIRE_MESSAGE(img, img.error().message);
  CHECK(img->pixel(32, 32)[3] > 200);
  CHECK(img->pixel(2, 2)[3] == 0);
  // In bare mode the bone shell is not drawn: a pixel over the shell's rim but outside the sphere's
  // projection stays empty; the wdt table shows the shell.
  auto rim = s.camera.project({0, 0, 5.2}, 64, 64);
  REQUIRE(rim);
  const int rx = int(std::lround((*rim)[0])), ry = int(std::lround((*rim)[1]));
  CHECK(img->pixel(rx, ry)[3] == 0);
  s.preset.mode = RenderMode::Wdt;
  s.preset.t = 1;
  auto wdt = gl->render(s);
  REQUIRE(wdt);
  CHECK(wdt->pixel(rx, ry)[3] > 50);
}
