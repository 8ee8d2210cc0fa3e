#include "ui/window.h"

#include <SDL.h>
#include <imgui.h>
#include <backends/imgui_impl_opengl3.h>
#include <backends/imgui_impl_sdl.h>

#include <algorithm>
#include <filesystem>
#include <cstdlib>

#include "commands.h"
#include "render/gl/window_target.h"

namespace at::app {

// ---------------------------------------------------------------------------------------------
// A display to open a window on

bool displayAvailable() {
  if (const char* offscreen = std::getenv("AT_DESKTOP_OFFSCREEN"); offscreen && std::string(offscreen) == "1") {
    if (SDL_Init(SDL_INIT_VIDEO) != 0) return false;
    SDL_QuitSubSystem(SDL_INIT_VIDEO);
    return true;
  }
  bool named = false;
  for (const char* name : {"DISPLAY", "WAYLAND_DISPLAY"})
    if (const char* v = std::getenv(name); v && *v) named = true;
  if (!named) return false;
  // The variable may name a display that is gone (a closed SSH forwarding, a stopped Xvfb): only a
  // video subsystem that initialises means a window can be opened. SDL falls back to its offscreen
  // video driver when the named display fails, so the driver that came up must be a windowing one.
  if (SDL_Init(SDL_INIT_VIDEO) != 0) return false;
  const char* driver = SDL_GetCurrentVideoDriver();
  const bool windowing = driver && (std::string(driver) == "x11" || std::string(driver) == "wayland");
  SDL_QuitSubSystem(SDL_INIT_VIDEO);
  return windowing;
}

// ---------------------------------------------------------------------------------------------
// The window, its context and ImGui, torn down in the reverse order

struct DesktopWindow::State {
  bool sdl = false;
  SDL_Window* window = nullptr;
  SDL_GLContext context = nullptr;
  bool imgui = false, imguiSdl = false, imguiGl = false;
  ~State() {
    if (imguiGl) ImGui_ImplOpenGL3_Shutdown();
    if (imguiSdl) ImGui_ImplSDL2_Shutdown();
    if (imgui) ImGui::DestroyContext();
    if (context) SDL_GL_DeleteContext(context);
    if (window) SDL_DestroyWindow(window);
    if (sdl) SDL_Quit();
  }
};

DesktopWindow::DesktopWindow(std::unique_ptr<State> state) : state_(std::move(state)) {}
DesktopWindow::~DesktopWindow() = default;

namespace {

// The UI font: DejaVu Sans (Debian's fonts-dejavu-core) has the glyphs of the course texts and the
// app's messages (Latin-1, dashes, quotes, ellipsis, arrows, ×, ³, −, ≈, ≤, check marks). Where it
// is missing, ImGui's built-in font (ASCII only) is used.
const char* const kFontFiles[] = {"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                                  "/usr/share/fonts/dejavu/DejaVuSans.ttf"};
constexpr float kFontPixels = 15;
const ImWchar kFontRanges[] = {0x0020, 0x00FF, 0x2010, 0x205E, 0x2190, 0x21FF, 0x2200, 0x22FF,
                               0x25A0, 0x25FF, 0x2700, 0x27BF, 0};

// True when the UI font was loaded (else ImGui's default font stays).
bool loadUiFont(float uiScale) {
  for (const char* path : kFontFiles) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(path, ec)) continue;
    if (ImGui::GetIO().Fonts->AddFontFromFileTTF(path, kFontPixels * uiScale, nullptr, kFontRanges)) return true;
  }
  return false;
}

// ImGui's built-in font has no em dash.
std::string ascii(const std::string& text) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text.compare(i, 3, "\u2014") == 0) {
      out += '-';
      i += 2;
    } else {
      out += text[i];
    }
  }
  return out;
}

}  // namespace

Result<std::unique_ptr<DesktopWindow>> DesktopWindow::open(int width, int height, bool scripted) {
  auto s = std::make_unique<State>();
  s->sdl = SDL_Init(SDL_INIT_VIDEO | SDL_INIT_TIMER | SDL_INIT_EVENTS) == 0;
  if (!s->sdl) return fail(ErrorKind::Unavailable, std::string("SDL cannot start its video subsystem: ") + SDL_GetError());
  // OpenGL 4.5, then 4.3 core, then whatever the driver gives; `note` says which was taken.
  std::string note;
  // AT_GL_DEBUG=1: a debug context whose errors are printed inside the GL call that raised them.
  const char* debugEnv = std::getenv("AT_GL_DEBUG");
  const bool debugGl = debugEnv && *debugEnv && std::string(debugEnv) != "0";
  struct Attempt {
    int major, minor;
    bool core;
  };
  for (const Attempt a : {Attempt{4, 5, true}, Attempt{4, 3, true}, Attempt{0, 0, false}}) {
    SDL_GL_ResetAttributes();
    if (a.core) {
      SDL_GL_SetAttribute(SDL_GL_CONTEXT_PROFILE_MASK, SDL_GL_CONTEXT_PROFILE_CORE);
      SDL_GL_SetAttribute(SDL_GL_CONTEXT_MAJOR_VERSION, a.major);
      SDL_GL_SetAttribute(SDL_GL_CONTEXT_MINOR_VERSION, a.minor);
    }
    if (debugGl) SDL_GL_SetAttribute(SDL_GL_CONTEXT_FLAGS, SDL_GL_CONTEXT_DEBUG_FLAG);
    SDL_GL_SetAttribute(SDL_GL_DOUBLEBUFFER, 1);
    SDL_GL_SetAttribute(SDL_GL_DEPTH_SIZE, 0);
    Uint32 flags = SDL_WINDOW_OPENGL | SDL_WINDOW_ALLOW_HIGHDPI | SDL_WINDOW_SHOWN;
    if (!scripted) flags |= SDL_WINDOW_RESIZABLE;
    if (!s->window) {
      s->window = SDL_CreateWindow("Anatomy Tutor", SDL_WINDOWPOS_CENTERED, SDL_WINDOWPOS_CENTERED, width, height, flags);
      if (!s->window) return fail(ErrorKind::Unavailable, std::string("cannot open a window: ") + SDL_GetError());
    }
    s->context = SDL_GL_CreateContext(s->window);
    const std::string version = std::to_string(a.major) + "." + std::to_string(a.minor);
    if (s->context) {
      note = a.core ? "asked for OpenGL " + version + " core" : "no 4.x core context; took the driver's default";
      break;
    }
    note += std::string(a.core ? "OpenGL " + version + " core refused (" : "(") + SDL_GetError() + "); ";
  }
  if (!s->context) return fail(ErrorKind::Unavailable, "cannot create an OpenGL context: " + note);
  SDL_GL_MakeCurrent(s->window, s->context);
  if (debugGl && !render::gl::enableDebugOutput()) note += "; AT_GL_DEBUG: the driver gave no debug context";
  SDL_GL_SetSwapInterval(scripted ? 0 : 1);
  float ddpi = 96;
  if (SDL_GetDisplayDPI(0, &ddpi, nullptr, nullptr) != 0 || !(ddpi > 0)) ddpi = 96;
  const float uiScale = std::clamp(ddpi / 96.0f, 1.0f, 3.0f);

  IMGUI_CHECKVERSION();
  ImGui::CreateContext();
  s->imgui = true;
  ImGui::GetIO().IniFilename = nullptr;  // the layout is the app's, not a file beside the binary
  ImGui::StyleColorsDark();
  ImGui::GetStyle().ScaleAllSizes(uiScale);
  const bool uiFont = loadUiFont(uiScale);  // loaded at the scaled size: crisp
  ImGui::GetIO().FontGlobalScale = uiFont ? 1.0f : uiScale;
  s->imguiSdl = ImGui_ImplSDL2_InitForOpenGL(s->window, s->context);
  s->imguiGl = ImGui_ImplOpenGL3_Init("#version 150");
  if (!s->imguiSdl || !s->imguiGl) return fail(ErrorKind::Unavailable, "Dear ImGui could not start its SDL2/OpenGL3 backends");

  std::unique_ptr<DesktopWindow> window(new DesktopWindow(std::move(s)));
  window->glDescription_ = uiFont ? render::gl::currentContextDescription() : ascii(render::gl::currentContextDescription());
  window->glNote_ = note;
  window->uiScale_ = uiScale;
  return window;
}

ViewLayout DesktopWindow::layout() const {
  ViewLayout l;
  SDL_GetWindowSize(state_->window, &l.windowW, &l.windowH);
  SDL_GL_GetDrawableSize(state_->window, &l.framebufferW, &l.framebufferH);
  l.uiScale = uiScale_;
  return l;
}

bool DesktopWindow::waitEvent(SDL_Event& event, int timeoutMs) { return SDL_WaitEventTimeout(&event, timeoutMs) != 0; }
bool DesktopWindow::pollEvent(SDL_Event& event) { return SDL_PollEvent(&event) != 0; }
void DesktopWindow::forwardToImGui(const SDL_Event& event) { ImGui_ImplSDL2_ProcessEvent(&event); }
bool DesktopWindow::imguiWantsMouse() { return ImGui::GetIO().WantCaptureMouse; }
bool DesktopWindow::imguiWantsText() { return ImGui::GetIO().WantTextInput; }

void DesktopWindow::beginFrame() {
  ImGui_ImplOpenGL3_NewFrame();
  ImGui_ImplSDL2_NewFrame();
  ImGui::NewFrame();
}

Status DesktopWindow::endFrame(render::RgbaImage* screenshot) {
  ImGui::Render();
  const ViewLayout l = layout();
  render::gl::beginWindowFrame(l.framebufferW, l.framebufferH, {0.04f, 0.04f, 0.05f, 1.0f});
  ImGui_ImplOpenGL3_RenderDrawData(ImGui::GetDrawData());
  drawError_ = render::gl::takeGlError();
  Status read;
  if (screenshot) {
    auto image = render::gl::readWindow(l.framebufferW, l.framebufferH);
    if (image) *screenshot = std::move(*image);
    else read = tl::unexpected(image.error());
  }
  SDL_GL_SwapWindow(state_->window);
  render::gl::finishGl();
  return read;
}

}  // namespace at::app
