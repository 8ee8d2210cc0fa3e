#include "render/gl/egl_context.h"

#include <dlfcn.h>

#include <cstring>
#include <vector>

#include <epoxy/egl.h>
#include <epoxy/gl.h>

namespace at::render::gl {

struct EglContext::State {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;
  // Order: unbind, destroy the context, terminate the display, then drop this thread's EGL state.
  // GL objects must be gone before (their owners die before the EglContext). Must run before the
  // driver's own exit-time teardown, i.e. not from a static destructor.
  ~State() {
    if (display != EGL_NO_DISPLAY) {
      eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
      if (context != EGL_NO_CONTEXT) eglDestroyContext(display, context);
      eglTerminate(display);
      eglReleaseThread();
    }
  }
};

namespace {

std::string eglErrorName(EGLint e) {
  switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    default: return "EGL error " + std::to_string(e);
  }
}

bool hasExtension(const char* list, const char* name) {
  if (!list) return false;
  const std::size_t n = std::strlen(name);
  for (const char* p = std::strstr(list, name); p; p = std::strstr(p + 1, name))
    if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
  return false;
}

// Tries the device platform (NVIDIA, headless GPUs), then Mesa's surfaceless platform, then the
// default display; returns an initialised display or EGL_NO_DISPLAY.
EGLDisplay openDisplay(std::string& why) {
  const char* clientExts = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  std::vector<EGLDisplay> candidates;
  if (hasExtension(clientExts, "EGL_EXT_platform_device") && hasExtension(clientExts, "EGL_EXT_device_enumeration")) {
    EGLDeviceEXT devices[8];
    EGLint count = 0;
    if (eglQueryDevicesEXT(8, devices, &count))
      for (EGLint i = 0; i < count; ++i) {
        const char* devExts = eglQueryDeviceStringEXT(devices[i], EGL_EXTENSIONS);
        // Skip Mesa's software device here; the surfaceless platform below covers it.
        if (devExts && hasExtension(devExts, "EGL_MESA_device_software")) continue;
        candidates.push_back(eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT, devices[i], nullptr));
      }
  }
  if (hasExtension(clientExts, "EGL_MESA_platform_surfaceless"))
    candidates.push_back(eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr));
  candidates.push_back(eglGetDisplay(EGL_DEFAULT_DISPLAY));
  for (EGLDisplay d : candidates) {
    if (d == EGL_NO_DISPLAY) continue;
    EGLint major = 0, minor = 0;
    if (eglInitialize(d, &major, &minor)) return d;
    why = "eglInitialize failed (" + eglErrorName(eglGetError()) + ")";
  }
  if (why.empty()) why = "no EGL display could be opened";
  return EGL_NO_DISPLAY;
}

}  // namespace

EglContext::EglContext(std::unique_ptr<State> state) : state_(std::move(state)) {}
EglContext::~EglContext() = default;
EglContext::EglContext(EglContext&&) noexcept = default;
EglContext& EglContext::operator=(EglContext&&) noexcept = default;

Result<EglContext> EglContext::create() {
  // libepoxy loads libEGL on the first EGL call and aborts the whole process when it cannot; look
  // for it first so that a machine without EGL gets an error instead. The handle stays open (the
  // library is then already loaded when libepoxy asks for it).
  if (!dlopen("libEGL.so.1", RTLD_LAZY | RTLD_LOCAL)) {
    const char* reason = dlerror();
    return fail(ErrorKind::Unavailable, std::string("EGL: libEGL.so.1 could not be loaded (") + (reason ? reason : "unknown reason") +
                "); install the EGL library (Debian: libegl1)");
  }
  auto state = std::make_unique<State>();
  std::string why;
  state->display = openDisplay(why);
  if (state->display == EGL_NO_DISPLAY) return fail(ErrorKind::Unavailable, "EGL: " + why);
  if (!eglBindAPI(EGL_OPENGL_API)) return fail(ErrorKind::Unavailable, "EGL: eglBindAPI(OpenGL) failed (" + eglErrorName(eglGetError()) + ")");
  // EGL_SURFACE_TYPE defaults to windows, which headless displays lack: ask for pbuffer configs
  // first, then any desktop-GL config, then none at all (EGL_KHR_no_config_context).
  const EGLint pbufferAttribs[] = {EGL_SURFACE_TYPE, EGL_PBUFFER_BIT, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  const EGLint anyAttribs[] = {EGL_SURFACE_TYPE, 0, EGL_RENDERABLE_TYPE, EGL_OPENGL_BIT, EGL_NONE};
  EGLConfig config = nullptr;
  EGLint count = 0;
  const bool noConfig = hasExtension(eglQueryString(state->display, EGL_EXTENSIONS), "EGL_KHR_no_config_context");
  if ((!eglChooseConfig(state->display, pbufferAttribs, &config, 1, &count) || count == 0) &&
      (!eglChooseConfig(state->display, anyAttribs, &config, 1, &count) || count == 0)) {
    if (!noConfig) return fail(ErrorKind::Unavailable, "EGL: no config supports desktop OpenGL");
    config = EGL_NO_CONFIG_KHR;
  }
  const EGLint contextAttribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 3,
                                   EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  state->context = eglCreateContext(state->display, config, EGL_NO_CONTEXT, contextAttribs);
  if (state->context == EGL_NO_CONTEXT)
    return fail(ErrorKind::Unavailable, "EGL: cannot create an OpenGL 4.3 core context (" + eglErrorName(eglGetError()) + ")");
  if (!eglMakeCurrent(state->display, EGL_NO_SURFACE, EGL_NO_SURFACE, state->context))
    return fail(ErrorKind::Unavailable, "EGL: cannot make the context current without a surface (" + eglErrorName(eglGetError()) + ")");
  return EglContext(std::move(state));
}

Status EglContext::makeCurrent() const {
  if (!eglMakeCurrent(state_->display, EGL_NO_SURFACE, EGL_NO_SURFACE, state_->context))
    return fail(ErrorKind::Unavailable, "EGL: eglMakeCurrent failed (" + eglErrorName(eglGetError()) + ")");
  return {};
}

std::string EglContext::description() const {
  const auto str = [](GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? std::string(reinterpret_cast<const char*>(s)) : std::string("?");
  };
  return str(GL_RENDERER) + " — OpenGL " + str(GL_VERSION);
}

}  // namespace at::render::gl
