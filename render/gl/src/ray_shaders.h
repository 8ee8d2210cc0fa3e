// GLSL sources of the ray caster (render_settings.h documents the classification they implement).
#pragma once

namespace at::render::gl::shaders {

// One triangle covering the viewport.
extern const char* const kFullScreenVertex;
// castRay(pixel) and its uniforms; compiled after "#version", a line per RAY_* define.
extern const char* const kRayCaster;
// Entry points: every pixel of the viewport (fragment), and the compute entry that casts one set
// of lattice rows of a progressive image (progressive.cpp) or a whole image.
extern const char* const kFragmentMain;
extern const char* const kComputeMain;
// Builds the selected structure's smoothed mask in a box of voxels.
extern const char* const kMaskShader;

}  // namespace at::render::gl::shaders
