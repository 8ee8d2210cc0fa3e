#include "service_watchdog.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <utility>

namespace at::test {

namespace {

// The watchdog's shell: reads its standard input (the pipe) to the end, then stops the service
// and removes the folder if it is still there. $1 the stop script, $2 the folder.
constexpr const char* kWatch = "cat > /dev/null; if [ -d \"$2\" ]; then \"$1\" stop \"$2\"; rm -rf \"$2\"; fi";

}  // namespace

ServiceWatchdog::ServiceWatchdog(const std::string& stopScript, const std::string& folder) {
  int ends[2];
  if (::pipe2(ends, O_CLOEXEC) != 0) return;
  // Everything the child needs is ready before fork: after it, only async-signal-safe calls.
  const char* script = stopScript.c_str();
  const char* dir = folder.c_str();
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::setsid();  // not killed with the test's process group
    ::dup2(ends[0], 0);
    const int null = ::open("/dev/null", O_WRONLY);
    if (null >= 0) ::dup2(null, 1), ::dup2(null, 2);
    ::close_range(3, ~0U, 0);  // holds no other pipe of the test open (CTest waits on its output's)
    ::execl("/bin/sh", "sh", "-c", kWatch, "at-service-watchdog", script, dir, static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(ends[0]);
  if (pid < 0) {
    ::close(ends[1]);
    return;
  }
  writeEnd_ = ends[1];
  pid_ = pid;
}

void ServiceWatchdog::finish() {
  if (writeEnd_ >= 0) ::close(writeEnd_);
  if (pid_ > 0) {
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
  }
  writeEnd_ = -1;
  pid_ = -1;
}

ServiceWatchdog::~ServiceWatchdog() { finish(); }

ServiceWatchdog::ServiceWatchdog(ServiceWatchdog&& other) noexcept
    : writeEnd_(std::exchange(other.writeEnd_, -1)), pid_(std::exchange(other.pid_, -1)) {}

ServiceWatchdog& ServiceWatchdog::operator=(ServiceWatchdog&& other) noexcept {
  if (this != &other) {
    finish();
    writeEnd_ = std::exchange(other.writeEnd_, -1);
    pid_ = std::exchange(other.pid_, -1);
  }
  return *this;
}

}  // namespace at::test
