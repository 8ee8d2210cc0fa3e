// The subcommands of anatomy-tutor (ARCHITECTURE.md §7). Each takes the arguments after its name,
// writes its result to stdout, one-line errors to stderr, and returns the process exit status.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace at::app {

using Argv = std::vector<std::string>;

struct Command {
  const char* name;
  const char* summary;               // one line for `anatomy-tutor --help`
  int (*run)(const Argv& args);
};

// Every command, in the order `--help` lists them. Defined in main.cpp.
const std::vector<Command>& commands();

// Prints "anatomy-tutor: <message>" on stderr and returns 1 (or `status`).
int reportError(const std::string& message, int status = 1);

// Volume commands (cmd_volume.cpp)
int runDatasets(const Argv& args);
int runStructures(const Argv& args);
int runInfo(const Argv& args);
int runSlice(const Argv& args);

// Weighted distance transform (cmd_wdt.cpp)
int runWdt(const Argv& args);

// Rendering (cmd_render.cpp)
int runRender(const Argv& args);
int runFigureSheet(const Argv& args);  // cmd_figure_sheet.cpp
// The shipped presets: dataSubdirectory("presets") (data_paths.h).
std::filesystem::path defaultPresetsDir();

// Labelling from seed strokes (cmd_segment.cpp)
int runSegment(const Argv& args);

// The desktop application (desktop/ui/desktop_app.cpp)
int runDesktop(const Argv& args);
// A display server to open a window on: DISPLAY (X11) or WAYLAND_DISPLAY set and non-empty, and a
// windowing video driver coming up on it. For measuring the app on a headless GPU machine,
// AT_DESKTOP_OFFSCREEN=1 with SDL_VIDEODRIVER=offscreen accepts SDL's offscreen driver (an EGL
// pbuffer, no window shown). (desktop/ui/window.cpp)
bool displayAvailable();
// The no-display fallback of `anatomy-tutor` without arguments: renders the first lesson's first
// three views (360×270) of course `courseId` (empty: the default course) offscreen (EGL) into
// `outDir` as PNG files, printing one line per file. The built-in phantom is opened at 128³ so that
// this stays quick on two CPU cores. (cmd_default_views.cpp)
int writeDefaultViews(const std::filesystem::path& outDir, const std::string& courseId = {});

// Datasets and learning (cmd_import.cpp, cmd_play.cpp, cmd_progress.cpp)
int runImport(const Argv& args);
int runPlay(const Argv& args);
int runProgress(const Argv& args);
int runCourses(const Argv& args);
int runLessons(const Argv& args);
int runExam(const Argv& args);       // cmd_exam.cpp
int runAnalytics(const Argv& args);  // cmd_analytics.cpp
int runCourse(const Argv& args);     // cmd_course.cpp

// Preference studies (cmd_study.cpp)
int runStudy(const Argv& args);

// Classes on a class server and sending the outbox (cmd_class.cpp)
int runClass(const Argv& args);
int runSync(const Argv& args);
int runXapi(const Argv& args);  // cmd_xapi.cpp

}  // namespace at::app
