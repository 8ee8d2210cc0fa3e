// anatomy-tutor: entry point. Dispatches to a subcommand; with none, runs the default course.
// `main` catches at the top: anything unexpected becomes a one-line error and exit status 2.
#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>

#include "cli_args.h"
#include "commands.h"
#include "core/printable_text.h"

namespace at::app {

const std::vector<Command>& commands() {
  static const std::vector<Command> table = {
      {"datasets", "list the datasets that can be opened", runDatasets},
      {"structures", "list a dataset's structures", runStructures},
      {"info", "load any supported file or folder and describe it", runInfo},
      {"slice", "write a grey slice with label overlay as PNG", runSlice},
      {"wdt", "weighted distance field of a structure (CPU or CUDA), with --check against exact", runWdt},
      {"render", "render a structure in one of the paper's modes to PNG (offscreen)", runRender},
      {"figure-sheet", "lay rendered panels side by side with captions into one PNG (figure sheets)", runFigureSheet},
      {"segment", "label a dataset from seed strokes (grow from seeds, threshold islands) to NIfTI or .seg.nrrd", runSegment},
      {"desktop", "open the desktop app (explore; --ui-script replays actions, --screenshot saves)", runDesktop},
      {"import", "register a dataset (volume, labels, names) in the database", runImport},
      {"courses", "list the courses", runCourses},
      {"course", "author and share courses: new, validate, import, export (.atcourse packages), list", runCourse},
      {"lessons", "list the lessons of the courses", runLessons},
      {"play", "run a lesson in the terminal (answers from a file or typed)", runPlay},
      {"progress", "show a user's progress and what is due for review", runProgress},
      {"exam", "take a course's practical exam in the terminal (timed, labels hidden)", runExam},
      {"analytics", "a class's lesson completion, hardest structures, question difficulty, recall (--csv)", runAnalytics},
      {"study", "preference studies: register, run, status, export", runStudy},
      {"class", "classes on a class server: create, join with a code, roles, the class's progress", runClass},
      {"sync", "send the answers waiting for the class server (offline first)", runSync},
      {"xapi", "learning records or a study's ratings as xAPI statements (JSON) for an LMS", runXapi},
  };
  return table;
}

int reportError(const std::string& message, int status) {
  // Error messages quote outside text (names, file contents): one printable line.
  std::fprintf(stderr, "anatomy-tutor: %s\n", printableText(message, 4000).c_str());
  return status;
}

namespace {

void printUsage() {
  std::printf("Anatomy Tutor %s — regional anatomy on CT with weighted distance fields\n\n", AT_VERSION);
  std::printf("usage: anatomy-tutor [--db PATH] [--user NAME] [--size WxH] [COMMAND] [ARGS…]\n"
              "  no command: the desktop app on the default course (desktop options such as\n"
              "  --ui-script F.json also work alone). The global options --db (the database file),\n"
              "  --user (whose progress) and --size (window or image size) may stand before the\n"
              "  command or after it.\n\n");
  for (const Command& c : commands()) std::printf("  %-12s %s\n", c.name, c.summary);
  std::printf("\n`anatomy-tutor COMMAND --help` describes each command. Courses, presets and studies are read from\n"
              "../share/anatomy-tutor beside the executable; AT_DATA_DIR=DIR reads them from DIR instead.\n");
}

// The desktop app on the default course (or --course ID's) when a display exists; otherwise one line
// saying so and that course's first lesson's first views written as PNG files through the offscreen
// renderer. `globals`: global and desktop options given without a command (`anatomy-tutor --db X`).
int runDefault(const Argv& globals) {
  if (displayAvailable()) return runDesktop(globals);
  std::string course;
  for (std::size_t i = 0; i + 1 < globals.size(); ++i)
    if (globals[i] == "--course") course = globals[i + 1];
  const std::string dir = "anatomy-tutor-views";
  std::printf("anatomy-tutor: no display (none named in DISPLAY/WAYLAND_DISPLAY, or it cannot be opened): writing the %s lesson's "
              "first views to %s/ instead\n", course.empty() ? "default" : ("'" + course + "' course's first").c_str(), dir.c_str());
  return writeDefaultViews(dir, course);
}

// `anatomy-tutor --course ID` with nothing else but global options starts as `anatomy-tutor` does
// (the desktop, or the course's first views where there is no display); other desktop options
// without a command, and the explicit `desktop` command, open the desktop.
bool startsOnCourse(const Argv& argv, const Argv& args) {
  if (std::find(argv.begin(), argv.end(), "desktop") != argv.end()) return false;
  bool course = false;
  for (std::size_t i = 0; i < args.size(); i += 2) {
    const std::string& word = args[i];
    if (word == "--course" && i + 1 < args.size()) course = true;
    else if (word != "--db" && word != "--user" && word != "--size") return false;
  }
  return course;
}

}  // namespace
}  // namespace at::app

int main(int argc, char** argv) {
  using namespace at::app;
  try {
    auto line = at::cli::splitCommandLine(Argv(argv + 1, argv + argc));
    if (!line) return reportError(line.error().message + " (see anatomy-tutor --help)", 2);
    const std::string& name = line->command;
    if (name == "--help" || name == "-h" || name == "help") {
      printUsage();
      return 0;
    }
    if (name == "--version") {
      std::printf("anatomy-tutor %s\n", AT_VERSION);
      return 0;
    }
    if (name.empty() || (name == "desktop" && startsOnCourse(Argv(argv + 1, argv + argc), line->args)))
      return runDefault(line->args);
    for (const Command& c : commands())
      if (name == c.name) return c.run(line->args);
    return reportError("unknown command '" + name + "' (see anatomy-tutor --help)", 2);
  } catch (const std::bad_alloc&) {
    return reportError("out of memory", 2);
  } catch (const std::exception& e) {
    return reportError(std::string("internal error: ") + e.what(), 2);
  }
}
