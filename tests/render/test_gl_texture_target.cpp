// renderToTexture: the desktop's view draws the ray caster's texture as it is. Its texels must be
// the image render() reads back for the same settings (rows bottom first, as GL stores them).
#include <doctest/doctest.h>

#include <epoxy/gl.h>

#include <vector>

#include "render/gl/volume_renderer.h"
#include "render/scene.h"
#include "render_fixture.h"
#include "render_scenes.h"

using namespace at;
using namespace at::render;

TEST_CASE("RenderToTexture_HoldsTheImageRenderReadsBack_BottomRowFirst") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  const test::Scene& scene = test::chambersScene();
  REQUIRE(gl->setVolume(scene.dataset.volume, scene.dataset.labels));
  REQUIRE(gl->setField(scene.weighted));
  gl->setSelected(1);
  RenderSettings s;
  s.width = 96;
  s.height = 64;  // not square: rows and columns cannot be confused
  s.camera = Camera::named(NamedView::Anterior, {0, 0, 0}, 12);
  s.background = {0.1f, 0.2f, 0.3f, 1.0f};
  auto image = gl->render(s);
  REQUIRE(image);
  auto shown = gl->renderToTexture(s);
  REQUIRE(shown);
  CHECK(shown->handle != 0);
  CHECK(shown->texelsWide == 96);
  CHECK(shown->texelsHigh == 64);
  CHECK(shown->uv0 == std::array<float, 2>{0, 0});
  CHECK(shown->uv1 == std::array<float, 2>{1, 1});
  std::vector<std::uint8_t> texels(std::size_t(96) * 64 * 4);
  glBindTexture(GL_TEXTURE_2D, GLuint(shown->handle));
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glGetTexImage(GL_TEXTURE_2D, 0, GL_RGBA, GL_UNSIGNED_BYTE, texels.data());
  REQUIRE(glGetError() == GL_NO_ERROR);
  int differing = 0, lit = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 96; ++x)
      for (int c = 0; c < 4; ++c) {
        const std::uint8_t fromTexture = texels[(std::size_t(63 - y) * 96 + std::size_t(x)) * 4 + std::size_t(c)];
        const std::uint8_t readBack = image->rgba[(std::size_t(y) * 96 + std::size_t(x)) * 4 + std::size_t(c)];
        differing += fromTexture != readBack;
        lit += c == 0 && readBack > 40;
      }
  CHECK(differing == 0);
  CHECK(lit > 0);  // the scene is drawn, not only the background
}
