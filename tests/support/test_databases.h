// The engine storage tests run on. By default SQLite files in the test's temporary folder; with
// AT_TEST_BACKEND=postgres the same tests run on a real PostgreSQL server: AT_TEST_POSTGRES_URL
// when set (a server someone runs; the URL of a database the tests may create schemas in), else
// the cluster CTest's `postgres` fixture started for all tests (AT_TEST_POSTGRES_CLUSTER names the
// file that holds its folder: tests/support/test_postgres.sh), else a throwaway cluster this
// process starts with scripts/pg-cluster.sh (initdb + pg_ctl on a loopback port, as an
// unprivileged user when run as root) and removes at exit. Each fresh
// PostgreSQL database is a new schema of that server (the URL selects it with search_path), so a
// test costs milliseconds, not a CREATE DATABASE.
#pragma once

#include <cstdint>
#include <optional>
#include <set>
#include <string>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "service_watchdog.h"
#include "test_support.h"

namespace at::test {

// True when AT_TEST_BACKEND=postgres.
bool testingOnPostgres();

// Runs one SQL statement on the server at `url`: empty on success, else libpq's message.
std::string execOnServer(const std::string& url, const std::string& sql);

// Opens (and migrates) the database at `location`, failing the test with the error otherwise.
db::Database openAt(const std::string& location);
// The integer in the first column of the first row of `sql` (a count), failing the test on error.
std::int64_t scalarCount(db::Database& db, const std::string& sql);

// Where a fresh, empty database lives: `dir/name` on SQLite; on PostgreSQL the URL of a new,
// empty schema (`name` only labels it). When the PostgreSQL server cannot start, prints
// "SKIPPED: …" with the reason and ends the test run as a skip (status 0, or 77 for one case).
std::string freshDatabase(const TempDir& dir, const std::string& name = "t.db");

// A fresh PostgreSQL database whatever the mode (for the sync tests, which need a server beside
// the clients' SQLite files); nullopt after printing "SKIPPED: <what> …" when no server starts.
std::optional<std::string> freshPostgresDatabase(const char* what);

// A PostgreSQL cluster of one test's own (scripts/pg-cluster.sh, on a free loopback port), for
// tests of what clients do while the server is down: stopping it disturbs no test running beside
// (the shared cluster is never stopped). Stopped and its folder removed when the object dies.
class PrivatePostgres {
 public:
  // Starts the cluster; on failure (no PostgreSQL installed) freshDatabase() reports the skip.
  PrivatePostgres();
  ~PrivatePostgres();
  PrivatePostgres(const PrivatePostgres&) = delete;
  PrivatePostgres& operator=(const PrivatePostgres&) = delete;

  // The URL of a new, empty schema on it; nullopt after printing "SKIPPED: <what> …".
  std::optional<std::string> freshDatabase(const char* what);
  // pg_ctl stop (fast) and start again on the same port and folder: true when it worked.
  bool stop();
  bool restart();
  // The cluster's folder (empty if none could be made).
  const std::string& folder() const { return dir_; }
  bool started() const { return started_; }
  const std::string& whyNot() const { return whyNot_; }

 private:
  std::string dir_, url_, whyNot_;
  bool started_ = false;
  int schemas_ = 0;
  ServiceWatchdog watchdog_;  // stops the cluster if this process dies without the destructor
};

// Tables (and on SQLite their SQL, on PostgreSQL their columns with types, nullability and
// defaults, and their indexes): the schema as a comparable set.
std::set<std::string> schemaOf(db::Database& db);
bool tableExists(db::Database& db, const std::string& table);
// The first column of the first row `sql` gives on the PostgreSQL database `url`, read with libpq
// directly (not through db/, which refuses some databases); nullopt on error or no row.
std::optional<std::string> postgresValue(const std::string& url, const std::string& sql);
// Sets the stored schema version directly (to fake a database from a newer program).
void forceSchemaVersion(db::Database& db, int version);

}  // namespace at::test
