// Servers the tests start are stopped, and their folders removed, even when a test process is
// killed (a CTest timeout, kill -9) and its destructors never run (tests/support/service_watchdog.h).
#include <doctest/doctest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "service_watchdog.h"
#include "test_databases.h"
#include "test_support.h"

using namespace at::test;
namespace fs = std::filesystem;

namespace {

// Runs `body(die)` in a child process; the body calls die(report) while what it made is alive, and
// die sends the report and kills the child with SIGKILL (no destructor, no exit handler runs).
// Returns the report, once the child is gone.
template <class Body>
std::string reportOfKilledChild(Body body) {
  int ends[2];
  REQUIRE(::pipe2(ends, O_CLOEXEC) == 0);
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    ::close(ends[0]);
    body([&](const std::string& report) {
      (void)!::write(ends[1], report.data(), report.size());
      ::raise(SIGKILL);
    });
    ::_exit(1);
  }
  ::close(ends[1]);
  std::string report;
  char buf[256];
  for (ssize_t n; (n = ::read(ends[0], buf, sizeof buf)) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    REQUIRE(n > 0);
    report.append(buf, std::size_t(n));
  }
  ::close(ends[0]);
  int status = 0;
  REQUIRE(::waitpid(pid, &status, 0) == pid);
  CHECK(WIFSIGNALED(status));
  return report;
}

// Waits up to `seconds` for `done`.
template <class Done>
bool within(int seconds, Done done) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return true;
}

std::string fileText(const fs::path& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A stop script in `scratch` that appends "<argument count>|<$1>|<$2>" to scratch/calls.
fs::path recordingStopScript(const TempDir& scratch) {
  const fs::path script = scratch.path() / "stop.sh";
  std::ofstream(script) << "#!/bin/sh\nprintf '%s|%s|%s\\n' \"$#\" \"$1\" \"$2\" >> '" << (scratch.path() / "calls").string()
                        << "'\n";
  fs::permissions(script, fs::perms::owner_all);
  return script;
}

}  // namespace

TEST_CASE("A killed test's watchdog stops its service once, with the folder as one argument, and removes the folder") {
  TempDir scratch("at-watchdog");
  const fs::path stopScript = recordingStopScript(scratch), calls = scratch.path() / "calls";
  // A folder whose name a shell would take apart or run.
  const fs::path folder = scratch.path() / "svc $(touch pwned) `touch pwned2` 'q\" ;x";
  fs::create_directories(folder / "data");
  std::ofstream(folder / "data" / "file") << "x";

  const std::string report = reportOfKilledChild([&](auto die) {
    ServiceWatchdog watchdog(stopScript.string(), folder.string());
    die(watchdog.watching() ? "watching" : "not");
  });
  CHECK(report == "watching");
  CHECK(within(30, [&] { return !fs::exists(folder); }));
  CHECK(fileText(calls) == "2|stop|" + folder.string() + "\n");
  CHECK_FALSE(fs::exists(scratch.path() / "pwned"));
  CHECK_FALSE(fs::exists(fs::current_path() / "pwned"));
  CHECK_FALSE(fs::exists(fs::current_path() / "pwned2"));
}

TEST_CASE("A watchdog whose owner stopped the service and removed the folder does nothing") {
  TempDir scratch("at-watchdog");
  const fs::path stopScript = recordingStopScript(scratch), calls = scratch.path() / "calls";
  const fs::path folder = scratch.path() / "svc";
  fs::create_directories(folder);
  {
    ServiceWatchdog watchdog(stopScript.string(), folder.string());
    REQUIRE(watchdog.watching());
    fs::remove_all(folder);  // the owner's own clean stop
  }  // the destructor waits for the watchdog to end
  CHECK_FALSE(fs::exists(calls));
  // And a watchdog that is still watching leaves a live folder alone.
  fs::create_directories(folder);
  {
    ServiceWatchdog watchdog(stopScript.string(), folder.string());
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    CHECK(fs::exists(folder));
    CHECK_FALSE(fs::exists(calls));
    fs::remove_all(folder);
  }
}

TEST_CASE("A test process killed while its own PostgreSQL cluster runs leaves no server and no folder behind") {
  const std::string report = reportOfKilledChild([](auto die) {
    PrivatePostgres cluster;
    if (!cluster.started()) die("skip " + cluster.whyNot());
    std::ifstream pidFile(fs::path(cluster.folder()) / "data" / "postmaster.pid");
    std::string serverPid;
    std::getline(pidFile, serverPid);
    die(cluster.folder() + "\n" + serverPid);
  });
  if (report.rfind("skip ", 0) == 0) {
    skipf("the killed-test cleanup on a real server: %s", report.c_str() + 5);
    return;
  }
  const auto newline = report.find('\n');
  REQUIRE(newline != std::string::npos);
  const fs::path folder = report.substr(0, newline);
  const pid_t serverPid = pid_t(std::stol(report.substr(newline + 1)));
  REQUIRE(serverPid > 1);
  CHECK(within(60, [&] { return ::kill(serverPid, 0) != 0 && errno == ESRCH; }));
  CHECK(within(60, [&] { return !fs::exists(folder); }));
}

// The cluster the CTest fixture shares (tests/support/test_postgres.sh) outlives the script that
// starts it; a CTest run killed before its stop test would leave it running. The child here plays
// CTest: it runs the start script (its parent, as CTest is), checks that the server stays up while
// it lives, and is killed.
TEST_CASE("A CTest run killed while the fixture's shared PostgreSQL cluster runs leaves no server and no folder behind") {
  TempDir scratch("at-fixture");
  const fs::path listed = scratch.path() / "cluster.txt";
  const fs::path script = sourceDir() / "tests" / "support" / "test_postgres.sh";
  const std::string report = reportOfKilledChild([&](auto die) {
    const pid_t start = ::fork();
    if (start == 0) {
      const int null = ::open("/dev/null", O_WRONLY);
      ::dup2(null, STDOUT_FILENO);
      ::execlp("bash", "bash", script.c_str(), "start", listed.c_str(), static_cast<char*>(nullptr));
      ::_exit(127);
    }
    int status = 0;
    ::waitpid(start, &status, 0);
    if (!fs::exists(listed)) die("skip the start script made no cluster (exit " + std::to_string(WEXITSTATUS(status)) + ")");
    const std::string folder = fileText(listed).substr(0, fileText(listed).find('\n'));
    std::ifstream pidFile(fs::path(folder) / "data" / "postmaster.pid");
    std::string serverPid;
    std::getline(pidFile, serverPid);
    // The watcher polls every 2 s: the server must still be up after a few polls.
    std::this_thread::sleep_for(std::chrono::seconds(5));
    const bool alive = ::kill(pid_t(std::stol(serverPid)), 0) == 0;
    die(folder + "\n" + serverPid + "\n" + (alive ? "alive" : "stopped early"));
  });
  if (report.rfind("skip ", 0) == 0) {
    skipf("the killed CTest run's cluster: %s", report.c_str() + 5);
    return;
  }
  const auto first = report.find('\n'), second = report.find('\n', first + 1);
  REQUIRE(second != std::string::npos);
  const fs::path folder = report.substr(0, first);
  const pid_t serverPid = pid_t(std::stol(report.substr(first + 1, second - first - 1)));
  REQUIRE(serverPid > 1);
  CHECK(report.substr(second + 1) == "alive");
  CHECK(within(60, [&] { return ::kill(serverPid, 0) != 0 && errno == ESRCH; }));
  CHECK(within(60, [&] { return !fs::exists(folder); }));
  CHECK(within(10, [&] { return !fs::exists(listed); }));
}
