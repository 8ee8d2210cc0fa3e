// Typed, move-only owners of GL objects (internal to render/gl: nothing outside sees a GLuint).
// Each deletes its object when it dies; the GL context must be current then.
#pragma once

#include <utility>

#include <epoxy/gl.h>

namespace at::render::gl {

template <class Traits>
class GlObject {
 public:
  GlObject() = default;
  static GlObject make() {
    GlObject o;
    o.id_ = Traits::create();
    return o;
  }
  ~GlObject() {
    if (id_) Traits::destroy(id_);
  }
  GlObject(GlObject&& o) noexcept : id_(std::exchange(o.id_, 0)) {}
  GlObject& operator=(GlObject&& o) noexcept {
    if (this != &o) {
      if (id_) Traits::destroy(id_);
      id_ = std::exchange(o.id_, 0);
    }
    return *this;
  }
  GlObject(const GlObject&) = delete;
  GlObject& operator=(const GlObject&) = delete;
  GLuint id() const { return id_; }
  explicit operator bool() const { return id_ != 0; }

 private:
  GLuint id_ = 0;
};

struct TextureTraits {
  static GLuint create() { GLuint id = 0; glGenTextures(1, &id); return id; }
  static void destroy(GLuint id) { glDeleteTextures(1, &id); }
};
struct FramebufferTraits {
  static GLuint create() { GLuint id = 0; glGenFramebuffers(1, &id); return id; }
  static void destroy(GLuint id) { glDeleteFramebuffers(1, &id); }
};
struct RenderbufferTraits {
  static GLuint create() { GLuint id = 0; glGenRenderbuffers(1, &id); return id; }
  static void destroy(GLuint id) { glDeleteRenderbuffers(1, &id); }
};
struct VertexArrayTraits {
  static GLuint create() { GLuint id = 0; glGenVertexArrays(1, &id); return id; }
  static void destroy(GLuint id) { glDeleteVertexArrays(1, &id); }
};
struct QueryTraits {
  static GLuint create() { GLuint id = 0; glGenQueries(1, &id); return id; }
  static void destroy(GLuint id) { glDeleteQueries(1, &id); }
};
struct ProgramTraits {
  static GLuint create() { return glCreateProgram(); }
  static void destroy(GLuint id) { glDeleteProgram(id); }
};
struct VertexShaderTraits {
  static GLuint create() { return glCreateShader(GL_VERTEX_SHADER); }
  static void destroy(GLuint id) { glDeleteShader(id); }
};
struct ComputeShaderTraits {
  static GLuint create() { return glCreateShader(GL_COMPUTE_SHADER); }
  static void destroy(GLuint id) { glDeleteShader(id); }
};
struct FragmentShaderTraits {
  static GLuint create() { return glCreateShader(GL_FRAGMENT_SHADER); }
  static void destroy(GLuint id) { glDeleteShader(id); }
};

using Texture = GlObject<TextureTraits>;
using Framebuffer = GlObject<FramebufferTraits>;
using Renderbuffer = GlObject<RenderbufferTraits>;
using VertexArray = GlObject<VertexArrayTraits>;
using Query = GlObject<QueryTraits>;
using Program = GlObject<ProgramTraits>;
using VertexShader = GlObject<VertexShaderTraits>;
using FragmentShader = GlObject<FragmentShaderTraits>;
using ComputeShader = GlObject<ComputeShaderTraits>;

}  // namespace at::render::gl
