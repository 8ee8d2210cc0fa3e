// What a windowed GL context (the desktop app's SDL window) needs beyond the ray caster: the
// rendered image as a texture a UI toolkit can draw, the window's framebuffer cleared for a new
// frame, and the window read back for screenshots. All need the window's context current; the
// ray caster (volume_renderer.h) works in that same context.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>

#include "render/image.h"
#include "core/error.h"

namespace at::render::gl {

// An RGBA8 2-D texture holding the latest uploaded image, linear-filtered (the view may show a
// reduced-resolution render stretched to the full view while the user interacts).
class ImageTexture {
 public:
  static Result<ImageTexture> create();
  ~ImageTexture();
  ImageTexture(ImageTexture&&) noexcept;
  ImageTexture& operator=(ImageTexture&&) noexcept;

  Status upload(const RgbaImage& image);
  // The texture name as an opaque handle (ImTextureID); 0 before the first upload.
  std::uintptr_t handle() const;
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  struct State;
  explicit ImageTexture(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
  int width_ = 0, height_ = 0;
};

// "llvmpipe (LLVM 15.0.6, 256 bits) — OpenGL 4.5 (Core Profile) Mesa 22.3.6" for the current context.
std::string currentContextDescription();
// Major and minor version of the current context (e.g. {4, 5}).
std::array<int, 2> currentContextVersion();
// Binds the window's framebuffer, sets the viewport to it and clears it to `rgba`.
void beginWindowFrame(int width, int height, const std::array<float, 4>& rgba);
// Reads the window's framebuffer (the back buffer, before the swap) as an image, top row first.
Result<RgbaImage> readWindow(int width, int height);
// KHR_debug output for the current context (it needs a debug context: SDL_GL_CONTEXT_DEBUG_FLAG):
// synchronous, so that the message comes inside the call that raised it; errors go to stderr as
// "GL debug: …" lines. Returns false when the context offers no debug output.
bool enableDebugOutput();
// Reads the GL error flag: the error's name ("GL_INVALID_OPERATION"), empty when none is set.
std::string takeGlError();
// Waits until the GL has finished every command issued so far (frame timing).
void finishGl();

}  // namespace at::render::gl
