// Running the desktop app on a UI script under Xvfb, as the desktop tests do.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_support.h"

namespace at::test {

inline bool haveXvfb() { return std::system("command -v xvfb-run >/dev/null 2>&1") == 0; }

// For the top of a desktop test: true when xvfb-run is there; otherwise prints why the test is
// skipped (as requireSharedData does) and returns false.
inline bool requireXvfb() {
  if (haveXvfb()) return true;
  at::test::skipf("xvfb-run is not installed");
  return false;
}

struct DesktopOptions {
  std::string dataset = "phantom:128";
  std::string size = "800x480";      // a small window: software GL on two shared cores is slow
  double renderScale = 0.4;          // the volume image at this fraction of the view's resolution
  std::filesystem::path db;          // empty: the test process's temporary data folder's database
  std::string user;                  // --user, when not empty
  std::string screenshot;            // --screenshot, when not empty
};

struct DesktopRun {
  int exitCode = -1;
  std::vector<nlohmann::json> events;  // the JSON lines the scripted mode prints
  std::string err;
};

// Writes `script` into `dir` and runs the app on it under xvfb-run. The app's exit status comes
// from a wrapper inside xvfb-run: xvfb-run's own status at times reports a failed clean-up of its
// temporary folder instead.
inline DesktopRun runDesktopScript(const TempDir& dir, const nlohmann::json& script, const DesktopOptions& options = {}) {
  namespace fs = std::filesystem;
  const fs::path scriptPath = dir / "script.json", out = dir / "stdout", err = dir / "stderr", wrapper = dir / "run.sh",
                 status = dir / "status";
  std::ofstream(scriptPath) << script.dump();
  fs::remove(status);
  {
    std::ofstream w(wrapper);
    w << "'" << appBinary().string() << "' desktop --dataset '" << options.dataset << "' --size " << options.size
      << " --render-scale " << options.renderScale;
    if (!options.db.empty()) w << " --db '" << options.db.string() << "'";
    if (!options.user.empty()) w << " --user '" << options.user << "'";
    if (!options.screenshot.empty()) w << " --screenshot '" << options.screenshot << "'";
    w << " --ui-script '" << scriptPath.string() << "' >'" << out.string() << "' 2>'" << err.string() << "'\n"
      << "echo $? >'" << status.string() << "'\n";
  }
  const std::string cmd = "xvfb-run -a -s '-screen 0 1280x800x24' sh '" + wrapper.string() + "'";
  (void)std::system(cmd.c_str());
  DesktopRun r;
  std::ifstream statusIn(status);
  if (!(statusIn >> r.exitCode)) r.exitCode = -1;
  r.err = readFile(err);
  std::istringstream lines(readFile(out));
  for (std::string line; std::getline(lines, line);)
    if (!line.empty() && line[0] == '{') r.events.push_back(nlohmann::json::parse(line, nullptr, false));
  return r;
}

// The desktop on a laptop screen: `actions` on the 128³ phantom in a 1280×720 window (at the
// default render scale), with progress in `db` under `user`. The window size the layout tests
// check the panels against.
inline constexpr int kLaptopWidth = 1280, kLaptopHeight = 720;
inline DesktopRun runLaptopScript(const TempDir& dir, const nlohmann::json& actions, const std::filesystem::path& db,
                                  const std::string& user) {
  DesktopOptions options;
  options.size = std::to_string(kLaptopWidth) + "x" + std::to_string(kLaptopHeight);
  options.db = db;
  options.user = user;
  return runDesktopScript(dir, {{"actions", actions}}, options);
}

// The events of one kind ({"event": kind, …}), in order.
inline std::vector<nlohmann::json> eventsOf(const std::vector<nlohmann::json>& events, const std::string& kind) {
  std::vector<nlohmann::json> found;
  for (const nlohmann::json& e : events)
    if (e.is_object() && e.value("event", "") == kind) found.push_back(e);
  return found;
}
inline std::vector<nlohmann::json> eventsOf(const DesktopRun& r, const std::string& kind) { return eventsOf(r.events, kind); }

}  // namespace at::test
