// Writing a learner's event into the outbox (class_server.h), from inside the transaction that
// records the answer or attempt it describes, so that the outbox holds exactly what was stored.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "database.h"

namespace at::db {

struct ClassEvent {
  std::string kind;  // "answer", "lesson_started", "lesson_finished"
  std::int64_t occurredAt = 0;
  std::string lessonId;
  std::string questionId;
  std::string structure;
  std::optional<int> correct;
  std::optional<double> score;
  std::string payload = "{}";  // JSON object: the whole record
};

// Inside the caller's write transaction: when the local user `userId` has joined a class, writes
// `event` into the outbox with a fresh UUID, addressed to that class and server; otherwise nothing.
Status enqueueClassEvent(Database& d, std::int64_t userId, const ClassEvent& event);

}  // namespace at::db
