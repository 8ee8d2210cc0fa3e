// CUDA–GL interop for the renderer: copies a device-resident distance field (DeviceField,
// wdt_cuda.h) into an OpenGL 3-D texture without a round trip through host memory. Plain C++:
// neither CUDA nor GL types appear here; only render/gl calls it, with its own texture's name.
#pragma once

#include <memory>

#include "core/error.h"

namespace at::cuda {

class DeviceField;

// A GL 3-D texture (R32F, allocated by the caller) registered with CUDA for writing. Registration
// is costly; keep one per texture storage (re-register after the texture is re-allocated). The
// GL context that owns the texture must be current when this is created, used and destroyed.
class GlTextureTarget {
 public:
  // Errors carry the failing CUDA call ("cudaGraphicsGLRegisterImage: invalid argument").
  static Result<GlTextureTarget> registerTexture(unsigned glTexture3d, int width, int height, int depth);
  ~GlTextureTarget();
  GlTextureTarget(GlTextureTarget&&) noexcept;
  GlTextureTarget& operator=(GlTextureTarget&&) noexcept;
  GlTextureTarget(const GlTextureTarget&) = delete;
  GlTextureTarget& operator=(const GlTextureTarget&) = delete;

  // Copies the field device-to-array into the texture. Error if the field's dims differ from the
  // texture's or a CUDA call fails. Synchronous with respect to the host.
  Status copyFrom(const DeviceField& field);

  struct Impl;

 private:
  explicit GlTextureTarget(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace at::cuda
