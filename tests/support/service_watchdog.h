// A server a test starts (a PostgreSQL cluster, PgBouncer) is stopped, and its folder removed, even
// when the test process is killed (a CTest timeout, a developer's Ctrl-C or kill -9) and its
// destructors never run: a small process of its own session waits for the end of a pipe that only
// the test process holds open, and when the pipe ends runs `<stop script> stop <folder>` and
// removes the folder if the folder is still there.
#pragma once

#include <sys/types.h>

#include <string>

namespace at::test {

class ServiceWatchdog {
 public:
  ServiceWatchdog() = default;
  // Watches `folder`; `stopScript` is called as `stopScript stop folder` (scripts/pg-cluster.sh,
  // scripts/pgbouncer.sh). watching() is false if the process could not be started.
  ServiceWatchdog(const std::string& stopScript, const std::string& folder);
  // Ends the watch: the watchdog stops what is left (nothing, after the owner's own clean stop)
  // and is waited for.
  ~ServiceWatchdog();
  ServiceWatchdog(const ServiceWatchdog&) = delete;
  ServiceWatchdog& operator=(const ServiceWatchdog&) = delete;
  ServiceWatchdog(ServiceWatchdog&& other) noexcept;
  ServiceWatchdog& operator=(ServiceWatchdog&& other) noexcept;

  bool watching() const { return pid_ > 0; }

 private:
  void finish();
  int writeEnd_ = -1;
  pid_t pid_ = -1;
};

}  // namespace at::test
