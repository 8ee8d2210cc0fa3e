// Helpers shared by the test suites: where the real data lives, temporary folders, random seeds,
// running the anatomy-tutor binary.
#pragma once

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "core/error.h"

namespace at {
struct Dataset;
}

namespace at::test {

// A skip: prints "SKIPPED: <message>" (printf-style) and records it. A test process that ran one
// test case, skipped in it and failed nothing exits with kSkippedExitCode, which CTest (which runs
// each case on its own) reports as a skip; a failure still fails. Every skip goes through here.
void skipf(const char* format, ...) __attribute__((format(printf, 1, 2)));
// What the process should return: `status` (doctest's) unless it is 0, one case ran and it skipped.
int exitStatusWithSkips(int status);
inline constexpr int kSkippedExitCode = 77;
// Test cases this process started (counted by doctest_main's listener).
std::atomic<int>& testCasesStarted();

// The synthetic phantom at size³ voxels, built once per size for the whole test run (256³ takes
// about half a second).
const Dataset& phantomOfSize(int size);

// ../shared/data next to the checkout, or empty if it is absent (tests then report a skip).
std::filesystem::path sharedDataDir();
// Full path of a file under shared/data; empty if shared/data is absent.
std::filesystem::path sharedData(const std::string& relative);
// True and nothing printed if present; otherwise prints "SKIPPED: <what> needs ../shared/data".
bool requireSharedData(const char* what);

// The message of a failed Result, or "" for a value: safe inside doctest's *_MESSAGE macros, which
// `-s` stringifies on success too.
template <class T>
std::string errorText(const Result<T>& result) {
  return result ? std::string() : result.error().message;
}

// Runs `command` in a shell: its standard output, and its exit status in `status` (-1 when it
// could not run or did not exit).
std::string runCommand(const std::string& command, int& status);

// The whole content of a file (empty if it cannot be read).
std::string readFile(const std::filesystem::path& path);

// The project's source tree (for data/ files).
std::filesystem::path sourceDir();

// A fresh, empty temporary folder removed when the object dies.
class TempDir {
 public:
  explicit TempDir(const std::string& prefix = "at-test");
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// A fresh seed per run (time-based) unless AT_TEST_SEED is set; printed so a failure can be replayed.
std::uint64_t freshSeed(const char* testName);

// Runs the anatomy-tutor binary with `args` (shell-quoted by the caller) and captures stdout,
// stderr and the exit status. The binary is found from the build tree.
struct CommandResult {
  int exitCode = -1;
  std::string out;
  std::string err;
};
std::filesystem::path appBinary();
// True and nothing printed if appBinary() exists; otherwise prints "SKIPPED: <what> needs the
// anatomy-tutor binary, not built in this tree" (a build without the app, such as the GPU one).
bool requireAppBinary(const char* what);
CommandResult runApp(const std::string& args, const std::string& stdinText = "");

}  // namespace at::test
