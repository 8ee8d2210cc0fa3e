// An offscreen OpenGL 4.3+ core context through EGL, without a window: Mesa's surfaceless
// platform (llvmpipe where there is no GPU), or the EGL device platform (NVIDIA's EGL). The
// context is made current on the creating thread; rendering goes to framebuffer objects.
// Lifetime: destroy every object holding GL resources (VolumeRenderer) before the EglContext, and
// destroy the EglContext before main returns — never from a static destructor: drivers (NVIDIA's
// EGL, CUDA) tear themselves down at exit first, and a late eglTerminate then crashes.
#pragma once

#include <memory>
#include <string>

#include "core/error.h"

namespace at::render::gl {

class EglContext {
 public:
  // Errors name the step that failed ("eglInitialize failed (EGL_NOT_INITIALIZED)") — callers
  // such as tests report a skip when no display can be created.
  static Result<EglContext> create();
  ~EglContext();
  EglContext(EglContext&&) noexcept;
  EglContext& operator=(EglContext&&) noexcept;
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;

  // "llvmpipe (LLVM 15.0.6, 256 bits) — OpenGL 4.5 (Core Profile) Mesa 22.3.6"
  std::string description() const;
  Status makeCurrent() const;

 private:
  struct State;
  explicit EglContext(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

}  // namespace at::render::gl
