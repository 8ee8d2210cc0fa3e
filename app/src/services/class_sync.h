// Sending a learner's waiting class events (db/class_server.h) from the programs they learn in —
// terminal `play` and the desktop — without holding the lesson up when the class server is away.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "db/class_server.h"

namespace at::app {

class OutboxSender {
 public:
  // `retryAfter`: how long to leave an unreachable server alone before trying again (a server
  // that is away may take libpq's connect timeout, two seconds or more, to say so).
  explicit OutboxSender(db::Database& local, std::chrono::seconds retryAfter = std::chrono::seconds(30));

  // After a record was written: pushes whatever waits in the outbox, unless the last push failed
  // less than `retryAfter` ago (then nothing is tried). Returns a line for the learner when the
  // state changed — the server could not be reached (how many events wait), or it was reached
  // again after that — and an empty string otherwise.
  std::string sendWaiting();
  // Pushes now whatever the last failure was (at the end of a lesson); same line as above.
  std::string sendNow();

  bool offline() const { return offline_; }

 private:
  db::Database& local_;
  db::ServerConnections connections_;  // kept open between answers
  std::chrono::seconds retryAfter_;
  std::chrono::steady_clock::time_point lastFailure_{};
  bool offline_ = false;
};

// The desktop's sender: an OutboxSender on a thread of its own, trying every `period` (and at
// once after wake()), so that neither a slow nor an absent server ever holds a frame up. The
// local connection serialises its calls (db/), so the UI thread keeps using it meanwhile. Lines
// for the learner are kept until the UI thread takes them.
class BackgroundOutboxSender {
 public:
  BackgroundOutboxSender(db::Database& local, std::chrono::milliseconds period,
                         std::chrono::seconds retryAfter = std::chrono::seconds(30));
  // Stops the thread (a push under way is finished first) and tries once more to send what
  // waits, unless the server was found away within `retryAfter` (at most a connect timeout).
  ~BackgroundOutboxSender();
  BackgroundOutboxSender(const BackgroundOutboxSender&) = delete;
  BackgroundOutboxSender& operator=(const BackgroundOutboxSender&) = delete;

  void wake();
  std::vector<std::string> takeLines();

 private:
  void run();
  OutboxSender sender_;
  std::chrono::milliseconds period_;
  std::mutex mutex_;
  std::condition_variable changed_;
  bool stop_ = false, woken_ = false;
  std::vector<std::string> lines_;
  std::thread thread_;  // last: starts once everything above exists
};

// One line for the learner about a sync: "class server: 12 events sent" / "… unreachable: …".
std::string describeSync(const db::SyncReport& report);

}  // namespace at::app
