// A class server as a lab sets it up for many machines: a throwaway PostgreSQL cluster with few
// connection slots (scripts/pg-cluster.sh, AT_PG_MAX_CONNECTIONS) and PgBouncer in front of it in
// transaction mode (scripts/pgbouncer.sh). Both are stopped and their folders removed when the
// object dies. PgBouncer does not pass libpq's `options` (the search_path the other tests select
// a schema with), so each fresh database here is a database of its own.
#pragma once

#include <optional>
#include <string>

#include "service_watchdog.h"

namespace at::test {

class PooledPostgres {
 public:
  // Starts both; on failure `whyNot()` says why (no PostgreSQL, no PgBouncer installed).
  PooledPostgres(int serverConnections, int poolSize);
  ~PooledPostgres();
  PooledPostgres(const PooledPostgres&) = delete;
  PooledPostgres& operator=(const PooledPostgres&) = delete;

  bool ok() const { return whyNot_.empty(); }
  const std::string& whyNot() const { return whyNot_; }
  // A new, empty database: its URL on the server itself and through the pooler.
  struct Urls {
    std::string direct, pooled;
  };
  std::optional<Urls> freshDatabase();

 private:
  std::string clusterDir_, bouncerDir_, serverUrl_, pooledUrl_, whyNot_;
  bool clusterStarted_ = false, bouncerStarted_ = false;
  int databases_ = 0;
  // Stop both if this process dies without the destructor (the pooler's is declared last, so it
  // is ended first, as the destructor stops the pooler before the server).
  ServiceWatchdog clusterWatchdog_, bouncerWatchdog_;
};

// A fresh database through a pooler for `what`, or nullopt after printing "SKIPPED: <what> …".
std::optional<PooledPostgres::Urls> pooledDatabase(PooledPostgres& server, const char* what);

}  // namespace at::test
