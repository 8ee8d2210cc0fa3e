// The GPU ray caster (ARCHITECTURE.md §4): HU, labels and the distance field as 3-D textures, the
// mode's 2-D table as a texture, front-to-back compositing with early termination, jittered ray
// starts, Phong shading from gradients and a clipping plane, into an offscreen framebuffer read
// back as an RGBA8 image. Samples are classified as render_settings.h documents (the same rules
// CPU picking uses). Needs a current OpenGL 4.3 core context (EglContext) for its whole life.
#pragma once

#include <cstdint>
#include <memory>

#include "render/image.h"
#include "render/render_settings.h"
#include "core/error.h"

namespace at::cuda {
class DeviceField;
}

namespace at::render::gl {

// Where the rays are cast: a compute shader (one invocation per pixel, the default) or a
// fragment shader over a full-screen triangle. Both run the same ray code and give the same
// image; the choice is for benchmarks (on NVIDIA's headless EGL, compute ran faster).
enum class RayCaster { Compute, Fragment };

class VolumeRenderer {
 public:
  // Compiles the shaders. Errors carry the GLSL log.
  static Result<VolumeRenderer> create();
  ~VolumeRenderer();
  VolumeRenderer(VolumeRenderer&&) noexcept;
  VolumeRenderer& operator=(VolumeRenderer&&) noexcept;

  // Uploads HU and labels (labels on the volume's grid). Replaces any previous volume and
  // drops the field.
  Status setVolume(const Volume& volume, const LabelMap& labels);
  // Uploads a distance field on its own grid (the volume's or a coarser one); +inf stays "far".
  Status setField(const FloatVolume& field);
  // Uploads `field` a few z-slices per call, for a frame loop that must not stall: software GL
  // takes ~0.2 s for a whole 256³ float field. Each call uploads slices until about `budgetMs` of
  // wall time has passed (at least one slice) into a second texture; the field shown (and
  // rendered) stays the previous one until the last slice is in, when the two textures swap and
  // the call returns true. The texture replaced is kept as the next upload's target; when none of
  // these dims exists, allocating it is the first call's only work. A call with another field
  // (another address or grid) starts over; the caller keeps `field` alive and unchanged until the
  // call that returns true. setVolume drops an upload in progress.
  Result<bool> uploadFieldStep(const FloatVolume& field, double budgetMs);
  // Copies a field that lives in CUDA device memory straight into the field texture (CUDA–GL
  // interop, no host round trip). Error when built without CUDA or when a CUDA call fails.
  Status setFieldFromDevice(const cuda::DeviceField& field);
  // Whether this build has the interop path (AT_HAVE_CUDA).
  static bool hasCudaInterop();
  void clearField();
  void setSelected(std::uint16_t label) { selected_ = label; }
  void setRayCaster(RayCaster rayCaster);

  // Renders one frame and reads it back.
  Result<RgbaImage> render(const RenderSettings& settings);
  // Renders one frame without reading it back; returns the GPU time of the draw in ms
  // (GL_TIME_ELAPSED), for benchmarks.
  Result<double> renderTimed(const RenderSettings& settings);

 private:
  struct State;
  explicit VolumeRenderer(std::unique_ptr<State> state);
  Status draw(const RenderSettings& settings);
  std::unique_ptr<State> state_;
  std::uint16_t selected_ = 0;
};

}  // namespace at::render::gl
