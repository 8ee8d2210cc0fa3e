#include "test_databases.h"

#include <libpq-fe.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>

#include <doctest/doctest.h>

namespace at::test {

namespace fs = std::filesystem;

namespace {

// The server the tests use, started once per process.
struct TestServer {
  std::string baseUrl;       // a database the tests make schemas in
  std::string clusterDir;    // the cluster's folder (never stopped by a test: PrivatePostgres)
  bool ownCluster = false;   // this process started the cluster (and stops it at exit)
  std::string whyNot;        // why there is no server
  ServiceWatchdog watchdog;  // stops the own cluster if the process dies without its exit handlers
};

// A script's output without its trailing newlines.
std::string runScript(const std::string& command, int& status) {
  std::string out = runCommand(command, status);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

std::string scriptPath() { return (sourceDir() / "scripts" / "pg-cluster.sh").string(); }


void stopAtExit();

TestServer& server() {
  static std::once_flag once;
  static TestServer s;
  std::call_once(once, [] {
    if (const char* url = std::getenv("AT_TEST_POSTGRES_URL"); url && *url) {
      s.baseUrl = url;
      if (auto e = execOnServer(s.baseUrl, "SELECT 1"); !e.empty()) s.whyNot = "AT_TEST_POSTGRES_URL does not answer: " + e;
      return;
    }
    // A cluster CTest's fixture started for all tests: AT_TEST_POSTGRES_CLUSTER names the file
    // that holds its folder (tests/support/test_postgres.sh).
    std::string shared;
    if (const char* listed = std::getenv("AT_TEST_POSTGRES_CLUSTER"); listed && *listed) {
      std::ifstream in(listed);
      std::getline(in, shared);
    }
    if (!shared.empty() && fs::exists(shared)) {
      int status = 0;
      const std::string url = runScript("'" + scriptPath() + "' url '" + shared + "' 2>&1", status);
      if (status != 0) {
        s.whyNot = "the tests' cluster in " + shared + " has no URL: " + url;
        return;
      }
      s.clusterDir = shared;
      s.baseUrl = url.substr(0, url.rfind('/')) + "/attest";
      if (auto e = execOnServer(s.baseUrl, "SELECT 1"); !e.empty()) s.whyNot = "the tests' cluster does not answer: " + e;
      return;
    }
    std::string dir = (fs::temp_directory_path() / "at-pg-test-XXXXXX").string();
    if (!::mkdtemp(dir.data())) {
      s.whyNot = "cannot make a folder for the test cluster";
      return;
    }
    s.watchdog = ServiceWatchdog(scriptPath(), dir);
    int status = 0;
    const std::string url = runScript("AT_PG_FAST=1 '" + scriptPath() + "' start '" + dir + "' 2>&1", status);
    if (status != 0) {
      s.whyNot = url.empty() ? "scripts/pg-cluster.sh failed" : url;
      std::error_code ec;
      fs::remove_all(dir, ec);
      return;
    }
    s.clusterDir = dir;
    s.ownCluster = true;
    std::atexit(stopAtExit);
    // The tests' database beside the maintenance one.
    if (auto e = execOnServer(url, "CREATE DATABASE attest"); !e.empty()) {
      s.whyNot = "cannot create the test database: " + e;
      return;
    }
    s.baseUrl = url.substr(0, url.rfind('/')) + "/attest";
  });
  return s;
}

void stopAtExit() {
  TestServer& s = server();
  if (!s.ownCluster) return;
  int status = 0;
  runScript("'" + scriptPath() + "' stop '" + s.clusterDir + "' 2>&1", status);
  std::error_code ec;
  fs::remove_all(s.clusterDir, ec);
}

std::optional<std::string> newSchema(std::string& whyNot) {
  TestServer& s = server();
  if (!s.whyNot.empty()) {
    whyNot = s.whyNot;
    return std::nullopt;
  }
  static std::atomic<int> counter{0};
  const std::string schema = "t" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
  if (auto e = execOnServer(s.baseUrl, "CREATE SCHEMA " + schema); !e.empty()) {
    whyNot = "cannot create a schema on the test server: " + e;
    return std::nullopt;
  }
  const char separator = s.baseUrl.find('?') == std::string::npos ? '?' : '&';
  return s.baseUrl + separator + "options=-csearch_path%3D" + schema;
}

}  // namespace

std::string execOnServer(const std::string& url, const std::string& sql) {
  PGconn* conn = PQconnectdb(url.c_str());
  std::string error;
  if (PQstatus(conn) != CONNECTION_OK) {
    error = PQerrorMessage(conn);
  } else {
    PGresult* r = PQexec(conn, sql.c_str());
    if (PQresultStatus(r) != PGRES_COMMAND_OK && PQresultStatus(r) != PGRES_TUPLES_OK) error = PQresultErrorMessage(r);
    PQclear(r);
  }
  PQfinish(conn);
  while (!error.empty() && error.back() == '\n') error.pop_back();
  return error;
}

db::Database openAt(const std::string& location) {
  auto db = db::Database::open(location);
  REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
  return std::move(*db);
}

std::int64_t scalarCount(db::Database& db, const std::string& sql) {
  auto s = db.prepare(sql);
  REQUIRE_MESSAGE(s, (s ? "" : s.error().message));
  auto row = s->step();
  REQUIRE_MESSAGE(row, (row ? "" : row.error().message));
  REQUIRE(*row);
  return s->int64(0);
}

bool testingOnPostgres() {
  const char* backend = std::getenv("AT_TEST_BACKEND");
  return backend && std::string(backend) == "postgres";
}

std::string freshDatabase(const TempDir& dir, const std::string& name) {
  if (!testingOnPostgres()) return (dir / name).string();
  std::string whyNot;
  auto url = newSchema(whyNot);
  if (!url) {
    at::test::skipf("the storage tests on PostgreSQL: %s", whyNot.c_str());
    std::fflush(stdout);
    std::_Exit(exitStatusWithSkips(0));
  }
  return *url;
}

std::optional<std::string> freshPostgresDatabase(const char* what) {
  std::string whyNot;
  auto url = newSchema(whyNot);
  if (!url) at::test::skipf("%s needs a PostgreSQL server: %s", what, whyNot.c_str());
  return url;
}

PrivatePostgres::PrivatePostgres() {
  dir_ = (fs::temp_directory_path() / "at-pg-private-XXXXXX").string();
  if (!::mkdtemp(dir_.data())) {
    whyNot_ = "cannot make a folder for the test's own cluster";
    dir_.clear();
    return;
  }
  watchdog_ = ServiceWatchdog(scriptPath(), dir_);
  int status = 0;
  url_ = runScript("AT_PG_FAST=1 '" + scriptPath() + "' start '" + dir_ + "' 2>&1", status);
  if (status != 0) {
    whyNot_ = url_.empty() ? "scripts/pg-cluster.sh failed" : url_;
    return;
  }
  started_ = true;
}

PrivatePostgres::~PrivatePostgres() {
  int status = 0;
  if (started_) runScript("'" + scriptPath() + "' stop '" + dir_ + "' 2>&1", status);
  std::error_code ec;
  if (!dir_.empty()) fs::remove_all(dir_, ec);
}

std::optional<std::string> PrivatePostgres::freshDatabase(const char* what) {
  if (!started_) {
    at::test::skipf("%s needs a PostgreSQL cluster of its own: %s", what, whyNot_.c_str());
    return std::nullopt;
  }
  const std::string schema = "t" + std::to_string(schemas_++);
  if (auto e = execOnServer(url_, "CREATE SCHEMA " + schema); !e.empty()) {
    at::test::skipf("%s: cannot create a schema on its own cluster: %s", what, e.c_str());
    return std::nullopt;
  }
  const char separator = url_.find('?') == std::string::npos ? '?' : '&';
  return url_ + separator + "options=-csearch_path%3D" + schema;
}

bool PrivatePostgres::stop() {
  if (!started_) return false;
  int status = 0;
  runScript("'" + scriptPath() + "' stop '" + dir_ + "' 2>&1", status);
  return status == 0;
}

bool PrivatePostgres::restart() {
  if (!started_) return false;
  int status = 0;
  runScript("'" + scriptPath() + "' restart '" + dir_ + "' 2>&1", status);
  return status == 0;
}

std::set<std::string> schemaOf(db::Database& db) {
  std::set<std::string> out;
  if (db.backend() == db::Backend::Sqlite) {
    auto s = db.prepare("SELECT type || ' ' || name || ': ' || coalesce(sql, '') FROM sqlite_master"
                        " WHERE name NOT LIKE 'sqlite_%'");
    REQUIRE(s);
    while (*s->step()) out.insert(s->text(0));
    return out;
  }
  auto columns = db.prepare(
      "SELECT table_name || '.' || column_name || ' ' || data_type || ' ' || is_nullable || ' ' ||"
      " coalesce(column_default, '') || ' #' || ordinal_position"
      " FROM information_schema.columns WHERE table_schema = current_schema()");
  REQUIRE(columns);
  while (*columns->step()) out.insert(columns->text(0));
  auto indexes = db.prepare("SELECT indexdef FROM pg_indexes WHERE schemaname = current_schema()");
  REQUIRE(indexes);
  while (*indexes->step()) {
    // Index definitions name the schema; each test database has its own.
    std::string def = indexes->text(0);
    const std::string on = " ON ";
    if (auto at = def.find(on); at != std::string::npos)
      if (auto dot = def.find('.', at); dot != std::string::npos) def.erase(at + on.size(), dot + 1 - at - on.size());
    out.insert(def);
  }
  return out;
}

bool tableExists(db::Database& db, const std::string& table) {
  auto s = db.backend() == db::Backend::Sqlite
               ? db.prepare("SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = ?1")
               : db.prepare("SELECT count(*) FROM information_schema.tables WHERE table_schema = current_schema()"
                            " AND table_name = ?1");
  REQUIRE(s);
  s->bind(1, table);
  REQUIRE(*s->step());
  return s->int64(0) > 0;
}

std::optional<std::string> postgresValue(const std::string& url, const std::string& sql) {
  PGconn* conn = PQconnectdb(url.c_str());
  std::optional<std::string> value;
  if (PQstatus(conn) == CONNECTION_OK) {
    PGresult* r = PQexec(conn, sql.c_str());
    if (PQresultStatus(r) == PGRES_TUPLES_OK && PQntuples(r) > 0) value = std::string(PQgetvalue(r, 0, 0));
    PQclear(r);
  }
  PQfinish(conn);
  return value;
}

void forceSchemaVersion(db::Database& db, int version) {
  if (db.backend() == db::Backend::Sqlite) {
    REQUIRE(db.exec("PRAGMA user_version = " + std::to_string(version)));
  } else {
    REQUIRE(db.exec("UPDATE at_schema_version SET version = " + std::to_string(version)));
  }
}

}  // namespace at::test
