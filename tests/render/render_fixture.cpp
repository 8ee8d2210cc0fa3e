#include "render_fixture.h"

#include <cstdio>
#include <memory>
#include <optional>

#include "render/gl/egl_context.h"

namespace at::test {

render::gl::VolumeRenderer* glRenderer() {
  static std::optional<render::gl::EglContext> context;
  static std::optional<render::gl::VolumeRenderer> renderer;
  static bool tried = false;
  static std::string why;
  if (!tried) {
    tried = true;
    auto ctx = render::gl::EglContext::create();
    if (!ctx) {
      why = ctx.error().message;
    } else {
      context.emplace(std::move(*ctx));
      auto r = render::gl::VolumeRenderer::create();
      if (!r) {
        why = r.error().message;
      } else {
        renderer.emplace(std::move(*r));
        std::printf("render tests on: %s\n", context->description().c_str());
      }
    }
  }
  if (!renderer) std::printf("SKIPPED: GL render test needs an EGL OpenGL 4.3 context (%s)\n", why.c_str());
  return renderer ? &*renderer : nullptr;
}

}  // namespace at::test
