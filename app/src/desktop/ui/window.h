// The desktop's window: SDL2 with an OpenGL context (4.5, 4.3 core, else the driver's default)
// and Dear ImGui on it, set up and torn down in order (RAII). Only ui/ sees SDL and ImGui.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include "core/error.h"
#include "desktop_model.h"
#include "render/image.h"

union SDL_Event;

namespace at::app {

class DesktopWindow {
 public:
  // Opens a window of `width`×`height` logical pixels; a scripted run gets a fixed-size window
  // and no vsync. Errors: no video subsystem, no window, no context, ImGui's backends.
  static Result<std::unique_ptr<DesktopWindow>> open(int width, int height, bool scripted);
  ~DesktopWindow();
  DesktopWindow(const DesktopWindow&) = delete;
  DesktopWindow& operator=(const DesktopWindow&) = delete;

  // The GL context in ASCII ("llvmpipe (LLVM 15.0.6, 256 bits) - OpenGL 4.5 …"), and which
  // context was asked for.
  const std::string& glDescription() const { return glDescription_; }
  const std::string& glNote() const { return glNote_; }
  float uiScale() const { return uiScale_; }
  ViewLayout layout() const;

  // Waits up to `timeoutMs` for an event (0: only polls); false when none came.
  bool waitEvent(SDL_Event& event, int timeoutMs);
  bool pollEvent(SDL_Event& event);
  // ImGui sees every event; true when ImGui wants the mouse (the pointer is over a panel) or the
  // keyboard (text is being typed).
  static void forwardToImGui(const SDL_Event& event);
  static bool imguiWantsMouse();
  static bool imguiWantsText();

  void beginFrame();  // a new ImGui frame
  // Renders ImGui over the cleared window; `screenshot` (not empty): then reads the window back
  // into it. Swaps and waits for the GL to finish (frame timing). A GL error the UI's drawing
  // raised is read here (so that the volume renderer's next call does not take it for its own)
  // and kept for takeDrawError().
  Status endFrame(render::RgbaImage* screenshot);
  // The GL error the last endFrame's UI drawing raised ("GL_INVALID_OPERATION"), once; empty: none.
  std::string takeDrawError() { return std::exchange(drawError_, {}); }

 private:
  struct State;
  explicit DesktopWindow(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
  std::string glDescription_, glNote_, drawError_;
  float uiScale_ = 1;
};

}  // namespace at::app
