// The PostgreSQL engine (libpq): a class server's database. Statements are sent with their
// parameters (PQexecParams; integers as int8, reals as float8, text left for the server to type)
// and read as text. The schema version lives in the one-row table at_schema_version. Write
// transactions take one transaction-scoped advisory lock, so writers of this program follow each
// other as they do on SQLite and a repository's read-then-write never races another's.
#include <libpq-fe.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <mutex>
#include <optional>
#include <string_view>
#include <vector>

#include "backend.h"

namespace at::db::detail {

namespace {

constexpr unsigned kInt8Oid = 20, kFloat8Oid = 701;
// pg_advisory_xact_lock key of the program's writers ("AT" in ASCII).
constexpr const char* kWriterLock = "SELECT pg_advisory_xact_lock(16724)";

// True for a statement that cannot change data when sent twice: BEGIN, or a SELECT (this
// program's SELECTs outside transactions only read).
bool changesNothing(std::string_view sql) {
  const auto start = sql.find_first_not_of(" \t\r\n");
  if (start == std::string_view::npos) return true;
  const auto word = sql.substr(start, 6);
  const auto is = [&](std::string_view w) {
    if (word.size() < w.size()) return false;
    for (std::size_t i = 0; i < w.size(); ++i)
      if (std::toupper(static_cast<unsigned char>(word[i])) != w[i]) return false;
    return true;
  };
  return sql.substr(start) == "BEGIN" || is("SELECT");
}

std::string firstLine(const char* message) {
  std::string s = message ? message : "";
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  if (auto nl = s.find('\n'); nl != std::string::npos) s = s.substr(0, nl);
  return s;
}

// Why a connection could not be made, in one line. A server (or pooler) that is full says so in
// its text only (libpq gives no SQLSTATE before the connection exists): PostgreSQL's "too many
// clients already" / "remaining connection slots are reserved", PgBouncer's "no more connections
// allowed (max_client_conn)". Those get what to do instead of the raw error.
std::string connectFailure(const std::string& name, PGconn* conn) {
  const std::string raw = firstLine(PQerrorMessage(conn));
  const auto says = [&](const char* text) { return raw.find(text) != std::string::npos; };
  if (says("too many clients") || says("remaining connection slots") || says("max_client_conn"))
    return "the database server " + name + " is full (" + raw + "): connect the lab machines through PgBouncer " +
           "(scripts/pgbouncer.sh, README \"Many lab machines\") or raise the server's max_connections";
  return "cannot reach the database server " + name + ": " + raw;
}

bool contentionState(const std::string& state) {
  return state == "40001" || state == "40P01" || state == "55P03";
}

// The kind of a failed statement from its SQLSTATE (PostgreSQL appendix A).
ErrorKind kindOf(const std::string& state) {
  if (state == "23505") return ErrorKind::Conflict;
  // Refusals of a class server's functions and grants (class_security_sql.cpp).
  if (state == "42501" || state == "42710") return ErrorKind::Conflict;
  if (state == "P0002") return ErrorKind::NotFound;
  // A study participant withdrawn, or resumed by a later session (study_writes_sql.cpp).
  if (state == "55000") return ErrorKind::Conflict;
  if (state == "22023") return ErrorKind::Invalid;
  if (state == "23503") return ErrorKind::NotFound;
  if (state.rfind("23", 0) == 0) return ErrorKind::Invalid;
  if (contentionState(state) || state.rfind("08", 0) == 0 || state.rfind("57P", 0) == 0) return ErrorKind::Unavailable;
  return ErrorKind::Io;
}

void ignoreNotice(void*, const char*) {}

struct ResultClear {
  void operator()(PGresult* r) const { PQclear(r); }
};
using ResultPtr = std::unique_ptr<PGresult, ResultClear>;

class PostgresConnection;

class PostgresCursor final : public Cursor {
 public:
  PostgresCursor(PostgresConnection& connection, std::string sql, std::string original)
      : connection_(connection), sql_(std::move(sql)), original_(std::move(original)) {}

  void bindInt(int index, std::int64_t value) override { set(index, std::to_string(value), kInt8Oid); }
  void bindReal(int index, double value) override {
    if (std::isnan(value)) return set(index, "NaN", kFloat8Oid);
    if (std::isinf(value)) return set(index, value > 0 ? "Infinity" : "-Infinity", kFloat8Oid);
    char buf[40];
    std::snprintf(buf, sizeof buf, "%.17g", value);
    set(index, buf, kFloat8Oid);
  }
  void bindText(int index, std::string_view text) override {
    if (text.find('\0') != std::string_view::npos) {
      if (bindError_.empty())
        bindError_ = "binding parameter " + std::to_string(index) + ": PostgreSQL text cannot hold a NUL byte";
      return;
    }
    set(index, std::string(text), 0);
  }
  void bindNull(int index) override {
    if (!valid(index)) return;
    values_[std::size_t(index - 1)].reset();
    types_[std::size_t(index - 1)] = 0;
  }

  Result<bool> step() override;

  void reset() override {
    result_.reset();
    row_ = -1;
    values_.clear();
    types_.clear();
    bindError_.clear();
  }

  bool isNull(int column) const override { return PQgetisnull(result_.get(), row_, column) != 0; }
  std::int64_t int64(int column) const override {
    const char* v = PQgetvalue(result_.get(), row_, column);
    if (v[0] == 't' && v[1] == '\0') return 1;  // booleans come as t/f
    if (v[0] == 'f' && v[1] == '\0') return 0;
    return std::strtoll(v, nullptr, 10);
  }
  double real(int column) const override { return std::strtod(PQgetvalue(result_.get(), row_, column), nullptr); }
  std::string text(int column) const override {
    return std::string(PQgetvalue(result_.get(), row_, column), std::size_t(PQgetlength(result_.get(), row_, column)));
  }

 private:
  bool valid(int index) {
    if (index < 1 || index > 999) {
      if (bindError_.empty()) bindError_ = "binding parameter " + std::to_string(index) + ": index out of range";
      return false;
    }
    if (values_.size() < std::size_t(index)) {
      values_.resize(std::size_t(index));
      types_.resize(std::size_t(index), 0);
    }
    return true;
  }
  void set(int index, std::string value, unsigned type) {
    if (!valid(index)) return;
    values_[std::size_t(index - 1)] = std::move(value);
    types_[std::size_t(index - 1)] = type;
  }

  PostgresConnection& connection_;
  std::string sql_, original_;
  std::vector<std::optional<std::string>> values_;
  std::vector<Oid> types_;
  std::string bindError_;
  ResultPtr result_;
  int row_ = -1;
};

class PostgresConnection final : public Connection {
 public:
  PostgresConnection(PGconn* conn, std::string name) : conn_(conn), name_(std::move(name)) {
    PQsetNoticeProcessor(conn_, ignoreNotice, nullptr);
  }
  ~PostgresConnection() override { PQfinish(conn_); }
  PostgresConnection(const PostgresConnection&) = delete;
  PostgresConnection& operator=(const PostgresConnection&) = delete;

  Backend backend() const override { return Backend::Postgres; }
  const std::string& name() const override { return name_; }

  Result<std::unique_ptr<Cursor>> prepare(std::string_view sql) override {
    return std::unique_ptr<Cursor>(new PostgresCursor(*this, postgresPlaceholders(sql), std::string(sql)));
  }

  Status exec(std::string_view sql) override {
    auto r = run(std::string(sql), nullptr);
    if (!r) return tl::unexpected(r.error());
    return {};
  }

  int changes() const override { return changes_; }

  Status begin(bool write) override {
    if (auto s = exec("BEGIN"); !s) return s;
    transactionOpen_ = true;
    if (write) {
      if (auto s = exec(kWriterLock); !s) {
        rollback();
        return s;
      }
    }
    return {};
  }

  Status commit() override {
    auto r = run("COMMIT", nullptr);
    if (!r) return tl::unexpected(r.error());
    transactionOpen_ = false;
    // A transaction that failed earlier ends with ROLLBACK even when asked to commit.
    if (std::strcmp(PQcmdStatus(r->get()), "ROLLBACK") == 0)
      return fail(ErrorKind::Io, name_ + ": the transaction was rolled back by the server");
    return {};
  }

  void rollback() override {
    std::lock_guard lock(mutex_);
    if (PQstatus(conn_) == CONNECTION_OK) PQclear(PQexec(conn_, "ROLLBACK"));
    transactionOpen_ = false;
  }

  bool inTransaction() const override { return transactionOpen_; }

  bool lastFailureWasContention() const override { return contentionState(lastState_); }

  Result<int> schemaVersion() override {
    // Read pg_class with the statement's snapshot rather than to_regclass: name lookups use the
    // session's catalog cache, which still says "no such table" after another connection created
    // it while this one waited for the writer lock (two programs migrating a fresh database).
    auto exists = run("SELECT EXISTS (SELECT 1 FROM pg_catalog.pg_class c JOIN pg_catalog.pg_namespace n"
                      " ON n.oid = c.relnamespace WHERE c.relname = 'at_schema_version'"
                      " AND n.nspname = current_schema())", nullptr);
    if (!exists) return tl::unexpected(exists.error());
    if (std::strcmp(PQgetvalue(exists->get(), 0, 0), "t") != 0) return 0;
    auto version = run("SELECT max(version) FROM at_schema_version", nullptr);
    if (!version) return tl::unexpected(version.error());
    if (PQntuples(version->get()) == 0 || PQgetisnull(version->get(), 0, 0)) return 0;
    return std::atoi(PQgetvalue(version->get(), 0, 0));
  }

  Status setSchemaVersion(int version) override {
    return exec("CREATE TABLE IF NOT EXISTS at_schema_version (version INTEGER NOT NULL);"
                "DELETE FROM at_schema_version;"
                "INSERT INTO at_schema_version (version) VALUES (" + std::to_string(version) + ")");
  }

  // Runs `sql` (with parameters when `params` is given) and gives its result; errors carry the
  // SQLSTATE's kind. A connection that broke outside a transaction is re-established once first.
  struct Params {
    int count = 0;
    const Oid* types = nullptr;
    const char* const* values = nullptr;
  };
  Result<ResultPtr> run(const std::string& sql, const Params* params) {
    std::lock_guard lock(mutex_);
    lastState_.clear();
    // Outside a transaction a broken connection is opened again; inside one the transaction is
    // lost and the caller must start over.
    if (PQstatus(conn_) == CONNECTION_BAD && !transactionOpen_) PQreset(conn_);
    if (PQstatus(conn_) == CONNECTION_BAD) {
      lastState_ = "08006";
      return fail(ErrorKind::Unavailable, connectFailure(name_, conn_));
    }
    const auto send = [&] {
      return ResultPtr(params ? PQexecParams(conn_, sql.c_str(), params->count, params->types, params->values,
                                             nullptr, nullptr, 0)
                              : PQexec(conn_, sql.c_str()));
    };
    ResultPtr r = send();
    // A connection the server closed while idle (restart, idle timeout) is only noticed when a
    // statement fails on it. Outside a transaction a statement that changes nothing (BEGIN, a
    // SELECT) is sent once more on a new connection; a write is not, as it may have run.
    if (PQstatus(conn_) == CONNECTION_BAD && !transactionOpen_ && changesNothing(sql)) {
      PQreset(conn_);
      if (PQstatus(conn_) == CONNECTION_OK) r = send();
    }
    const auto status = r ? PQresultStatus(r.get()) : PGRES_FATAL_ERROR;
    if (status == PGRES_COMMAND_OK || status == PGRES_TUPLES_OK) {
      const char* tuples = PQcmdTuples(r.get());
      changes_ = tuples && *tuples ? std::atoi(tuples) : 0;
      return r;
    }
    const char* state = r ? PQresultErrorField(r.get(), PG_DIAG_SQLSTATE) : nullptr;
    lastState_ = state ? state : "08006";
    const std::string message = firstLine(r ? PQresultErrorMessage(r.get()) : PQerrorMessage(conn_));
    if (PQstatus(conn_) == CONNECTION_BAD)
      return fail(ErrorKind::Unavailable, "lost the connection to the database server " + name_ + ": " + message);
    return fail(kindOf(lastState_), "SQL error: " + message + (params ? " in: " + sql : std::string()));
  }

 private:
  PGconn* conn_;
  std::string name_;
  mutable std::mutex mutex_;  // libpq connections are not for concurrent use
  int changes_ = 0;
  std::string lastState_;
  bool transactionOpen_ = false;
};

Result<bool> PostgresCursor::step() {
  if (!result_) {
    if (!bindError_.empty()) return fail("SQL: " + bindError_ + " in: " + original_);
    std::vector<const char*> values(values_.size());
    for (std::size_t i = 0; i < values_.size(); ++i) values[i] = values_[i] ? values_[i]->c_str() : nullptr;
    PostgresConnection::Params params{int(values.size()), types_.data(), values.data()};
    auto r = connection_.run(sql_, &params);
    if (!r) return tl::unexpected(r.error());
    result_ = std::move(*r);
    row_ = -1;
  }
  ++row_;
  return row_ < PQntuples(result_.get());
}

}  // namespace

std::string postgresPlaceholders(std::string_view sql) {
  std::string out;
  out.reserve(sql.size());
  char quote = 0;
  for (std::size_t i = 0; i < sql.size(); ++i) {
    const char c = sql[i];
    if (quote) {
      if (c == quote) quote = 0;
    } else if (c == '\'' || c == '"') {
      quote = c;
    } else if (c == '?' && i + 1 < sql.size() && sql[i + 1] >= '0' && sql[i + 1] <= '9') {
      out += '$';
      continue;
    }
    out += c;
  }
  return out;
}

Result<std::unique_ptr<Connection>> openPostgres(const std::string& url, const OpenOptions& options) {
  const std::string timeout = std::to_string(std::max(2, options.connectTimeoutSeconds));
  const char* keywords[] = {"dbname", "connect_timeout", "application_name", "client_encoding", nullptr};
  const char* values[] = {url.c_str(), timeout.c_str(), "anatomy-tutor", "UTF8", nullptr};
  PGconn* raw = PQconnectdbParams(keywords, values, 1);
  if (!raw) return fail(ErrorKind::Io, "out of memory connecting to " + db::withoutPassword(url));
  auto connection = std::make_unique<PostgresConnection>(raw, db::withoutPassword(url));
  if (PQstatus(raw) != CONNECTION_OK)
    return fail(ErrorKind::Unavailable, connectFailure(db::withoutPassword(url), raw));
  // No session state: behind a pooler in transaction mode (PgBouncer, scripts/pgbouncer.sh) each
  // transaction may run on another server connection, so a SET here would apply to some other
  // client's transactions and not to ours. Nothing needs one: notices are ignored above, times are
  // written AT TIME ZONE 'UTC' (schema.cpp), statements are unnamed (PQexecParams) and the writers'
  // advisory lock is transaction-scoped. Reals come back exact from PostgreSQL 12 on (shortest
  // round-trip output by default); an older server needs the session setting.
  if (PQserverVersion(raw) > 0 && PQserverVersion(raw) < 120000)
    if (auto s = connection->exec("SET extra_float_digits = 3"); !s) return tl::unexpected(s.error());
  return std::unique_ptr<Connection>(std::move(connection));
}

}  // namespace at::db::detail

namespace at::db {

std::string withoutPassword(const std::string& url) {
  const auto scheme = url.find("://");
  if (scheme == std::string::npos) return url;
  const auto at = url.find('@', scheme + 3);
  if (at == std::string::npos) return url;
  const auto colon = url.find(':', scheme + 3);
  if (colon == std::string::npos || colon > at) return url;
  return url.substr(0, colon) + url.substr(at);
}

}  // namespace at::db
