// The SQLite engine: one file, WAL mode, foreign keys on, FULL sync, a busy timeout; the schema
// version in PRAGMA user_version.
#include <sqlite3.h>

#include <filesystem>

#include "backend.h"

namespace at::db::detail {

namespace {

namespace fs = std::filesystem;

std::string errorText(sqlite3* db, int rc) {
  if (db) return sqlite3_errmsg(db);
  return sqlite3_errstr(rc);
}

bool isBusyCode(int rc) {
  const int primary = rc & 0xff;
  return primary == SQLITE_BUSY || primary == SQLITE_LOCKED;
}

// The kind of a failed statement, from its extended result code: a uniqueness clash is a
// Conflict, a reference to a row that does not exist NotFound, another constraint Invalid, a lock
// held too long Unavailable, anything else (disk, corruption, SQL text) I/O.
ErrorKind kindOf(int rc) {
  switch (rc) {
    case SQLITE_CONSTRAINT_UNIQUE:
    case SQLITE_CONSTRAINT_PRIMARYKEY: return ErrorKind::Conflict;
    case SQLITE_CONSTRAINT_FOREIGNKEY: return ErrorKind::NotFound;
    default: break;
  }
  if ((rc & 0xff) == SQLITE_CONSTRAINT) return ErrorKind::Invalid;
  if (isBusyCode(rc)) return ErrorKind::Unavailable;
  return ErrorKind::Io;
}

class SqliteCursor final : public Cursor {
 public:
  SqliteCursor(sqlite3_stmt* stmt, sqlite3* db, std::string sql) : stmt_(stmt), db_(db), sql_(std::move(sql)) {}
  ~SqliteCursor() override { sqlite3_finalize(stmt_); }
  SqliteCursor(const SqliteCursor&) = delete;
  SqliteCursor& operator=(const SqliteCursor&) = delete;

  void bindInt(int index, std::int64_t value) override { note(sqlite3_bind_int64(stmt_, index, value), index); }
  void bindReal(int index, double value) override { note(sqlite3_bind_double(stmt_, index, value), index); }
  void bindText(int index, std::string_view text) override {
    // SQLITE_TRANSIENT: SQLite copies the bytes, so temporaries are safe to pass.
    note(sqlite3_bind_text64(stmt_, index, text.data(), text.size(), SQLITE_TRANSIENT, SQLITE_UTF8), index);
  }
  void bindNull(int index) override { note(sqlite3_bind_null(stmt_, index), index); }

  Result<bool> step() override {
    if (!bindError_.empty()) return fail("SQL: " + bindError_ + " in: " + sql_);
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    std::string message = errorText(db_, rc);
    // Leave the statement reusable after an error (its error code stays with the connection).
    const int code = sqlite3_extended_errcode(db_);
    sqlite3_reset(stmt_);
    return fail(kindOf(code), "SQL error: " + message);
  }

  void reset() override {
    sqlite3_reset(stmt_);
    sqlite3_clear_bindings(stmt_);
    bindError_.clear();
  }

  bool isNull(int column) const override { return sqlite3_column_type(stmt_, column) == SQLITE_NULL; }
  std::int64_t int64(int column) const override { return sqlite3_column_int64(stmt_, column); }
  double real(int column) const override { return sqlite3_column_double(stmt_, column); }
  std::string text(int column) const override {
    const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, column));
    const int n = sqlite3_column_bytes(stmt_, column);
    return p ? std::string(p, std::size_t(n)) : std::string();
  }

 private:
  void note(int rc, int index) {
    if (rc != SQLITE_OK && bindError_.empty())
      bindError_ = "binding parameter " + std::to_string(index) + ": " + errorText(db_, rc);
  }
  sqlite3_stmt* stmt_;
  sqlite3* db_;
  std::string sql_;
  std::string bindError_;
};

class SqliteConnection final : public Connection {
 public:
  SqliteConnection(sqlite3* db, std::string path) : db_(db), path_(std::move(path)) {}
  ~SqliteConnection() override { sqlite3_close_v2(db_); }
  SqliteConnection(const SqliteConnection&) = delete;
  SqliteConnection& operator=(const SqliteConnection&) = delete;

  Backend backend() const override { return Backend::Sqlite; }
  const std::string& name() const override { return path_; }

  Result<std::unique_ptr<Cursor>> prepare(std::string_view sql) override {
    sqlite3_stmt* stmt = nullptr;
    const int rc = sqlite3_prepare_v2(db_, sql.data(), int(sql.size()), &stmt, nullptr);
    if (rc != SQLITE_OK)
      return fail(kindOf(sqlite3_extended_errcode(db_)), "SQL error: " + errorText(db_, rc) + " in: " + std::string(sql));
    return std::unique_ptr<Cursor>(new SqliteCursor(stmt, db_, std::string(sql)));
  }

  Status exec(std::string_view sql) override {
    char* message = nullptr;
    const std::string text(sql);
    const int rc = sqlite3_exec(db_, text.c_str(), nullptr, nullptr, &message);
    if (rc != SQLITE_OK) {
      std::string m = message ? message : errorText(db_, rc);
      sqlite3_free(message);
      return fail(kindOf(sqlite3_extended_errcode(db_)), "SQL error: " + m);
    }
    return {};
  }

  int changes() const override { return sqlite3_changes(db_); }
  Status begin(bool write) override { return exec(write ? "BEGIN IMMEDIATE" : "BEGIN"); }
  Status commit() override { return exec("COMMIT"); }
  void rollback() override { sqlite3_exec(db_, "ROLLBACK", nullptr, nullptr, nullptr); }
  bool inTransaction() const override { return !sqlite3_get_autocommit(db_); }
  bool lastFailureWasContention() const override { return isBusyCode(sqlite3_extended_errcode(db_)); }

  Result<int> schemaVersion() override {
    auto stmt = prepare("PRAGMA user_version");
    if (!stmt) return tl::unexpected(stmt.error());
    auto row = (*stmt)->step();
    if (!row) return tl::unexpected(row.error());
    return *row ? int((*stmt)->int64(0)) : 0;
  }
  Status setSchemaVersion(int version) override { return exec("PRAGMA user_version = " + std::to_string(version)); }

 private:
  sqlite3* db_;
  std::string path_;
};

}  // namespace

Result<int> peekSqliteVersion(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec) || fs::file_size(path, ec) == 0) return 0;
  sqlite3* raw = nullptr;
  int rc = sqlite3_open_v2(path.c_str(), &raw, SQLITE_OPEN_READONLY, nullptr);
  if (rc != SQLITE_OK) {
    std::string message = errorText(raw, rc);
    sqlite3_close_v2(raw);
    return fail(ErrorKind::Io, path + ": cannot open: " + message);
  }
  sqlite3_busy_timeout(raw, 5000);
  sqlite3_stmt* stmt = nullptr;
  rc = sqlite3_prepare_v2(raw, "PRAGMA user_version", -1, &stmt, nullptr);
  int version = 0;
  if (rc == SQLITE_OK) {
    rc = sqlite3_step(stmt);
    if (rc == SQLITE_ROW) {
      version = sqlite3_column_int(stmt, 0);
      rc = SQLITE_OK;
    }
  }
  std::string message = rc == SQLITE_OK ? "" : errorText(raw, rc);
  sqlite3_finalize(stmt);
  sqlite3_close_v2(raw);
  if (rc != SQLITE_OK) {
    if ((rc & 0xff) == SQLITE_NOTADB) return fail(path + ": not an Anatomy Tutor database (not a SQLite file)");
    return fail(path + ": cannot read the schema version: " + message);
  }
  return version;
}

Result<std::unique_ptr<Connection>> openSqlite(const std::string& path, const OpenOptions& options) {
  sqlite3* raw = nullptr;
  const int flags = SQLITE_OPEN_READWRITE | (options.create ? SQLITE_OPEN_CREATE : 0) | SQLITE_OPEN_FULLMUTEX;
  const int rc = sqlite3_open_v2(path.c_str(), &raw, flags, nullptr);
  auto connection = std::make_unique<SqliteConnection>(raw, path);
  if (rc != SQLITE_OK) return fail(ErrorKind::Io, path + ": cannot open: " + errorText(raw, rc));
  sqlite3_extended_result_codes(raw, 1);
  sqlite3_busy_timeout(raw, options.busyTimeoutMs);

  // journal_mode needs the write lock briefly; busy_timeout covers a concurrent opener.
  {
    auto mode = connection->prepare("PRAGMA journal_mode = WAL");
    if (!mode) return tl::unexpected(mode.error());
    auto modeRow = (*mode)->step();
    if (!modeRow) return tl::unexpected(withContext(path + ": cannot switch to WAL", modeRow.error()));
  }
  if (auto s = connection->exec("PRAGMA foreign_keys = ON; PRAGMA synchronous = FULL"); !s)
    return tl::unexpected(withContext(path, s.error()));
  return std::unique_ptr<Connection>(std::move(connection));
}

}  // namespace at::db::detail
