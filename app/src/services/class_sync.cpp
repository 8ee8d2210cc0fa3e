#include "class_sync.h"

#include <algorithm>
#include <utility>

#include "core/strings.h"

namespace at::app {

OutboxSender::OutboxSender(db::Database& local, std::chrono::seconds retryAfter)
    : local_(local), retryAfter_(retryAfter) {}

std::string OutboxSender::sendWaiting() {
  if (offline_ && std::chrono::steady_clock::now() - lastFailure_ < retryAfter_) return "";
  return sendNow();
}

std::string OutboxSender::sendNow() {
  auto counts = db::outboxCounts(local_);
  if (!counts || counts->pending == 0) return "";
  auto report = db::syncOutbox(local_, {}, &connections_);
  if (!report) return "class events not sent: " + report.error().message;
  const bool wasOffline = offline_;
  offline_ = !report->complete();
  const bool refused = std::any_of(report->servers.begin(), report->servers.end(),
                                   [](const db::ServerSync& s) { return s.refused > 0; });
  if (refused) {  // the learner always hears what the server did not count, and why
    if (offline_) lastFailure_ = std::chrono::steady_clock::now();
    return describeSync(*report);
  }
  if (offline_) {
    lastFailure_ = std::chrono::steady_clock::now();
    return wasOffline ? "" : describeSync(*report);
  }
  return wasOffline ? describeSync(*report) : "";
}

BackgroundOutboxSender::BackgroundOutboxSender(db::Database& local, std::chrono::milliseconds period,
                                               std::chrono::seconds retryAfter)
    : sender_(local, retryAfter), period_(period), thread_([this] { run(); }) {}

BackgroundOutboxSender::~BackgroundOutboxSender() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  thread_.join();
  sender_.sendWaiting();  // what the last minutes left, before the program ends
}

void BackgroundOutboxSender::wake() {
  {
    std::lock_guard lock(mutex_);
    woken_ = true;
  }
  changed_.notify_all();
}

std::vector<std::string> BackgroundOutboxSender::takeLines() {
  std::lock_guard lock(mutex_);
  return std::exchange(lines_, {});
}

void BackgroundOutboxSender::run() {
  std::unique_lock lock(mutex_);
  while (!stop_) {
    changed_.wait_for(lock, period_, [this] { return stop_ || woken_; });
    if (stop_) break;
    woken_ = false;
    lock.unlock();
    std::string line = sender_.sendWaiting();
    lock.lock();
    if (!line.empty()) lines_.push_back(std::move(line));
  }
}

std::string describeSync(const db::SyncReport& report) {
  if (report.servers.empty()) return "class server: nothing to send";
  std::string line;
  for (const db::ServerSync& s : report.servers) {
    if (!line.empty()) line += "; ";
    line += "class server " + s.server + ": " + str::countOf(long(s.pushed), "event") + " sent";
    if (s.repeated) line += " (" + std::to_string(s.repeated) + " it already had)";
    if (s.refused) {
      line += ", " + str::countOf(long(s.refused), "event") + " refused:";
      for (std::size_t i = 0; i < s.refusals.size(); ++i) line += (i ? "; " : " ") + s.refusals[i];
      if (s.refused > std::int64_t(s.refusals.size())) line += "; …";
    }
    if (s.error) {
      line += ", " + str::countOf(long(s.pending), "event") + (s.pending == 1 ? " waits" : " wait") + " in the outbox (" +
              s.error->message + ")";
      if (s.error->kind == ErrorKind::Unavailable) line += " — sent when it is back, or with `anatomy-tutor sync`";
    }
  }
  return line;
}

}  // namespace at::app
