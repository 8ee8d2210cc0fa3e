// Shared by the render tests: one EGL context and ray caster per test process (created on first
// use), or nullptr after printing SKIPPED when no EGL display can be created.
#pragma once

#include "render/gl/volume_renderer.h"

namespace at::test {

render::gl::VolumeRenderer* glRenderer();

}  // namespace at::test
