// Fixtures for the course import safety tests: a legitimate package authored through the CLI, a
// snapshot of every file under a folder (to prove nothing outside the data folder changed), and
// a child run of the program with its peak memory measured.
#pragma once

#include <doctest/doctest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fcntl.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cli_checks.h"
#include "package/course_package.h"
#include "test_databases.h"
#include "test_support.h"

namespace at::test {

// Course "ear_tour" on the 32³ phantom imported as "ear_lab" in `dir`/a.db, exported to `package`.
inline void exportEarTour(const std::filesystem::path& dir, const std::filesystem::path& package, int size = 32) {
  namespace fs = std::filesystem;
  const Dataset& phantom = phantomOfSize(size);
  auto files = package::writeDatasetFiles(phantom, dir, true);
  REQUIRE_MESSAGE(files, errorText(files));
  nlohmann::json names = nlohmann::json::object();
  for (const Structure& s : phantom.structures) names[std::to_string(s.label)] = s.displayName;
  std::ofstream(dir / "names.json") << names.dump();
  const std::string db = " --db " + quotedPath(dir / "a.db");
  auto imported = runApp("import --volume " + quotedPath(dir / "volume.nrrd") + " --labels " + quotedPath(dir / "labels.nrrd") +
                         " --names " + quotedPath(dir / "names.json") + " --name ear_lab" + db);
  REQUIRE_MESSAGE(imported.exitCode == 0, imported.err);
  auto made = runApp("course new ear_tour --dataset ear_lab --title 'Ear tour' --out " + quotedPath(dir / "ear_tour.json") + db);
  REQUIRE_MESSAGE(made.exitCode == 0, made.err);
  auto stored = runApp("course import " + quotedPath(dir / "ear_tour.json") + db);
  REQUIRE_MESSAGE(stored.exitCode == 0, stored.err);
  auto exported = runApp("course export ear_tour --out " + quotedPath(package) + db);
  REQUIRE_MESSAGE(exported.exitCode == 0, exported.err);
}

// Every file and link under `root` (relative path → content, or "-> target"), skipping the
// database files named `skip` (their bytes change when only read) .
inline std::map<std::string, std::string> snapshotTree(const std::filesystem::path& root,
                                                      const std::vector<std::string>& skip = {}) {
  namespace fs = std::filesystem;
  std::map<std::string, std::string> out;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(root, ec); !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    const std::string rel = fs::relative(it->path(), root).string();
    bool skipped = false;
    for (const std::string& s : skip) skipped = skipped || rel.rfind(s, 0) == 0;
    if (skipped) continue;
    if (it->is_symlink()) out[rel] = "-> " + fs::read_symlink(it->path()).string();
    else if (it->is_regular_file()) out[rel] = readFile(it->path());
    else if (it->is_directory()) out[rel + "/"] = "";
  }
  return out;
}

struct MeasuredRun {
  int exitCode = -1;      // -signal when killed by one
  long peakKib = 0;       // the program's ru_maxrss
  double seconds = 0;
  std::string err;
};

// Runs the program with `args` (no shell) and measures its peak resident memory: through
// at_peak_memory (tests/support/peak_memory.cpp), so that what this test process holds is not
// counted as the program's.
inline MeasuredRun runAppMeasured(const std::vector<std::string>& args) {
  namespace fs = std::filesystem;
  TempDir dir("at-measured");
  const std::string helper = (fs::path(AT_BINARY_DIR) / "tests" / "at_peak_memory").string();
  const std::string report = (dir / "report").string(), errFile = (dir / "stderr").string();
  const std::string binary = appBinary().string();
  std::vector<char*> argv{const_cast<char*>(helper.c_str()), const_cast<char*>(report.c_str()),
                          const_cast<char*>(errFile.c_str()), const_cast<char*>(binary.c_str())};
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  timespec start{}, end{};
  clock_gettime(CLOCK_MONOTONIC, &start);
  const pid_t pid = fork();
  if (pid == 0) {
    execv(helper.c_str(), argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  clock_gettime(CLOCK_MONOTONIC, &end);
  MeasuredRun r;
  std::istringstream(readFile(report)) >> r.exitCode >> r.peakKib;
  REQUIRE_MESSAGE((WIFEXITED(status) && WEXITSTATUS(status) == 0), "at_peak_memory failed for " << binary);
  r.seconds = double(end.tv_sec - start.tv_sec) + 1e-9 * double(end.tv_nsec - start.tv_nsec);
  r.err = readFile(errFile);
  return r;
}

}  // namespace at::test
