// The desktop app's logic without a window: a DesktopModel on a real database and dataset, driven
// by the UI-script interpreter frame by frame as the window shell drives it, with no volume view
// (fields count as shown when they are ready; picking runs on the CPU as in the app). For the
// tests of what the desktop decides; what needs a window (screenshots, ImGui) runs under Xvfb.
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "desktop_model.h"
#include "desktop_script.h"
#include "script_interpreter.h"
#include "test_support.h"

namespace at::test {

struct HeadlessOptions {
  std::string dataset = "phantom:128";
  std::string course;                // --course: empty for the default course
  int width = 800, height = 480;     // the window's layout, as the Xvfb tests' windows
  double renderScale = 0.4;
  std::filesystem::path db;          // required
  std::string user;                  // empty: the default user
  double timeoutSeconds = 600;
  // Stands in for the window's panels: called once a frame after the model's frame began. Set,
  // the host counts as one that draws panels (actions that change a screen wait for it).
  std::function<void(app::DesktopModel&)> drawPanels;
};

struct HeadlessRun {
  int exitCode = -1;
  std::vector<nlohmann::json> events;
  std::string messages;               // every message to the user, one per line
  std::vector<std::string> screenshots;  // paths the script asked for (not written: no window)
};

// A script host without a window: screenshots are noted, not taken.
class NoWindow final : public app::ScriptHost {
 public:
  std::vector<std::string> requested;
  bool panels = false;
  void requestScreenshot(const std::string& path) override { requested.push_back(path); }
  bool screenshotPending() const override { return false; }
  std::string windowText() const override { return "headless"; }
  std::string glText() const override { return "none"; }
  bool drawsPanels() const override { return panels; }
};

inline app::ViewLayout headlessLayout(const HeadlessOptions& options) {
  app::ViewLayout layout;
  layout.windowW = layout.framebufferW = options.width;
  layout.windowH = layout.framebufferH = options.height;
  return layout;
}

inline HeadlessRun runHeadless(const nlohmann::json& script, const HeadlessOptions& options) {
  HeadlessRun run;
  auto session = app::LearningSession::open(options.db.string());
  if (!session) {
    run.messages = session.error().message;
    return run;
  }
  const render::PresetLibrary library(sourceDir() / "data" / "presets");
  app::DesktopOptions modelOptions;
  modelOptions.dataset = options.dataset;
  modelOptions.course = options.course;
  modelOptions.renderScale = options.renderScale;
  modelOptions.scripted = true;
  if (!options.user.empty()) modelOptions.userName = options.user;
  app::DesktopModel model(
      **session, library, modelOptions, [&](nlohmann::json e) { run.events.push_back(std::move(e)); },
      [&](const std::string& m) { run.messages += m + "\n"; });
  model.setLayout(headlessLayout(options));
  if (auto st = model.open(); !st) {
    run.messages += st.error().message + "\n";
    return run;
  }
  app::ScriptInterpreter interpreter(script.at("actions").get<std::vector<nlohmann::json>>(), std::nullopt);
  NoWindow host;
  host.panels = bool(options.drawPanels);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(options.timeoutSeconds);
  while (!interpreter.finished() && std::chrono::steady_clock::now() < deadline) {
    const auto start = app::Clock::now();
    interpreter.step(model, host, start);
    if (interpreter.finished()) break;
    model.beginFrame(nullptr);
    if (options.drawPanels) options.drawPanels(model);
    const auto end = app::Clock::now();
    model.endFrame(end, app::msBetween(start, end));
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  run.exitCode = interpreter.finished() ? interpreter.exitStatus() : -1;
  run.screenshots = host.requested;
  return run;
}

// The events of one kind ({"event": kind, …}), in order.
inline std::vector<nlohmann::json> eventsOf(const HeadlessRun& run, const std::string& kind) { return eventsOf(run.events, kind); }

// The lesson and exam panel tests' run: `actions` on the 128³ phantom as in an 800×600 window at
// render scale 0.3, with progress in `db` under `user`.
inline HeadlessRun runPanelScript(const nlohmann::json& actions, const std::filesystem::path& db, const std::string& user) {
  HeadlessOptions options;
  options.height = 600;
  options.renderScale = 0.3;
  options.db = db;
  options.user = user;
  return runHeadless({{"actions", actions}}, options);
}

}  // namespace at::test
