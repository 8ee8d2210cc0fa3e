#include "render/gl/window_target.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <vector>

#include "gl_objects.h"
#include "renderer_state.h"

namespace at::render::gl {

struct ImageTexture::State {
  GlObject<TextureTraits> texture;
};

ImageTexture::ImageTexture(std::unique_ptr<State> state) : state_(std::move(state)) {}
ImageTexture::~ImageTexture() = default;
ImageTexture::ImageTexture(ImageTexture&&) noexcept = default;
ImageTexture& ImageTexture::operator=(ImageTexture&&) noexcept = default;

Result<ImageTexture> ImageTexture::create() {
  auto state = std::make_unique<State>();
  state->texture = GlObject<TextureTraits>::make();
  if (!state->texture) return fail("image texture: glGenTextures failed (no current GL context?)");
  return ImageTexture(std::move(state));
}

Status ImageTexture::upload(const RgbaImage& image) {
  if (image.width <= 0 || image.height <= 0 || image.rgba.size() != std::size_t(image.width) * std::size_t(image.height) * 4)
    return fail("image texture: image of " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                " has no or inconsistent pixels");
  GLint previous = 0;
  glGetIntegerv(GL_TEXTURE_BINDING_2D, &previous);
  glBindTexture(GL_TEXTURE_2D, state_->texture.id());
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  if (image.width != width_ || image.height != height_) {
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, image.width, image.height, 0, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
    width_ = image.width;
    height_ = image.height;
  } else {
    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, image.width, image.height, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
  }
  glBindTexture(GL_TEXTURE_2D, GLuint(previous));
  if (const GLenum e = glGetError(); e != GL_NO_ERROR)
    return fail("image texture: uploading " + std::to_string(image.width) + "x" + std::to_string(image.height) +
                " failed (GL error " + std::to_string(e) + ")");
  return {};
}

std::uintptr_t ImageTexture::handle() const { return width_ > 0 ? std::uintptr_t(state_->texture.id()) : 0; }

std::string currentContextDescription() {
  const auto text = [](GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return text(GL_RENDERER) + " — OpenGL " + text(GL_VERSION);
}

std::array<int, 2> currentContextVersion() {
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  return {int(major), int(minor)};
}

void beginWindowFrame(int width, int height, const std::array<float, 4>& rgba) {
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  glViewport(0, 0, width, height);
  glClearColor(rgba[0], rgba[1], rgba[2], rgba[3]);
  glClear(GL_COLOR_BUFFER_BIT);
}

Result<RgbaImage> readWindow(int width, int height) {
  if (width <= 0 || height <= 0) return fail("screenshot: the window has no pixels");
  glBindFramebuffer(GL_READ_FRAMEBUFFER, 0);
  glReadBuffer(GL_BACK);
  RgbaImage image(width, height);
  std::vector<std::uint8_t> rows(image.rgba.size());
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glReadPixels(0, 0, width, height, GL_RGBA, GL_UNSIGNED_BYTE, rows.data());
  if (const GLenum e = glGetError(); e != GL_NO_ERROR)
    return fail("screenshot: reading the window back failed (GL error " + std::to_string(e) + ")");
  const std::size_t stride = std::size_t(width) * 4;
  for (int y = 0; y < height; ++y)  // GL's row 0 is the bottom
    std::copy_n(rows.data() + std::size_t(height - 1 - y) * stride, stride, image.rgba.data() + std::size_t(y) * stride);
  for (std::size_t i = 3; i < image.rgba.size(); i += 4) image.rgba[i] = 255;  // the window is opaque
  return image;
}

namespace {
void GLAPIENTRY printDebugMessage(GLenum source, GLenum type, GLuint id, GLenum severity, GLsizei length,
                                  const GLchar* message, const void*) {
  if (type != GL_DEBUG_TYPE_ERROR && severity != GL_DEBUG_SEVERITY_HIGH) return;
  std::fprintf(stderr, "GL debug: source 0x%x type 0x%x id %u: %.*s\n", unsigned(source), unsigned(type), unsigned(id),
               int(length < 0 ? std::strlen(message) : std::size_t(length)), message);
}
}  // namespace

std::string takeGlError() {
  const GLenum e = glGetError();
  return e == GL_NO_ERROR ? std::string() : glErrorName(e);
}

bool enableDebugOutput() {
  GLint flags = 0;
  glGetIntegerv(GL_CONTEXT_FLAGS, &flags);
  if (!(flags & GL_CONTEXT_FLAG_DEBUG_BIT)) return false;
  glEnable(GL_DEBUG_OUTPUT);
  glEnable(GL_DEBUG_OUTPUT_SYNCHRONOUS);
  glDebugMessageCallback(printDebugMessage, nullptr);
  return true;
}

void finishGl() { glFinish(); }

}  // namespace at::render::gl
