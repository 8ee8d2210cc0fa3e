// The SQLite engine: one file, WAL mode, foreign keys on, FULL sync, a busy timeout; the schema
// version in PRAGMA user_version. Files are inspected read-only (version, quick_check) before they
// are opened for writing; full disks, read-only and damaged files are said in those words.
#include <sqlite3.h>

#include <chrono>
#include <thread>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <filesystem>
#include <optional>

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

// The error of a failed SQLite call. What a user can act on — a full disk, a read-only or damaged
// database, a failing disk — is said in those words with the file named; anything else keeps
// SQLite's message and the kind from its result code.
Error sqliteError(sqlite3* db, int rc, const std::string& message) {
  const char* name = db ? sqlite3_db_filename(db, "main") : nullptr;
  const std::string file = name && *name ? std::string(name) + ": " : std::string();
  const std::string sqlite = " (SQLite: " + message + ")";
  // A disk I/O error is often a full or read-only disk underneath (the WAL index cannot grow).
  int primary = rc & 0xff;
  if (primary == SQLITE_IOERR || primary == SQLITE_CANTOPEN) {
    const int os = db ? sqlite3_system_errno(db) : 0;
    if (os == ENOSPC || os == EDQUOT) primary = SQLITE_FULL;
    if (os == EROFS || os == EACCES || os == EPERM) primary = SQLITE_READONLY;
  }
  switch (primary) {
    case SQLITE_FULL:
      return {ErrorKind::Io, file + "the disk is full" + sqlite +
                                 "; this step saved nothing — free some space and run the command again"};
    case SQLITE_READONLY:
      return {ErrorKind::Io, file + "the database is read-only" + sqlite +
                                 "; this command writes to it — give it write access or use another --db"};
    case SQLITE_CORRUPT:
    case SQLITE_NOTADB:
      return {ErrorKind::Io, file + "the database is damaged" + sqlite + "; restore a backup or use another --db"};
    case SQLITE_IOERR:
      return {ErrorKind::Io, file + "the disk failed to read or write the database" + sqlite};
    default:
      return {kindOf(rc), "SQL error: " + message};
  }
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
    return tl::unexpected(sqliteError(db_, code, message));
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
    if (rc != SQLITE_OK) {
      Error e = sqliteError(db_, sqlite3_extended_errcode(db_), errorText(db_, rc));
      if (e.message.rfind("SQL error: ", 0) == 0) e.message += " in: " + std::string(sql);
      return tl::unexpected(e);
    }
    return std::unique_ptr<Cursor>(new SqliteCursor(stmt, db_, std::string(sql)));
  }

  Status exec(std::string_view sql) override {
    char* message = nullptr;
    const std::string text(sql);
    const int rc = sqlite3_exec(db_, text.c_str(), nullptr, nullptr, &message);
    if (rc != SQLITE_OK) {
      std::string m = message ? message : errorText(db_, rc);
      sqlite3_free(message);
      return tl::unexpected(sqliteError(db_, sqlite3_extended_errcode(db_), m));
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

// "file:/path?mode=ro[&immutable=1]": a URI, so that read-only connections can ask for `immutable`.
std::string readOnlyUri(const std::string& path, bool immutable) {
  std::string uri = "file:";
  for (const char c : fs::absolute(path).string()) {
    if (c == '%' || c == '?' || c == '#') {
      char escaped[4];
      std::snprintf(escaped, sizeof escaped, "%%%02X", static_cast<unsigned char>(c));
      uri += escaped;
    } else {
      uri += c;
    }
  }
  return uri + (immutable ? "?mode=ro&immutable=1" : "?mode=ro");
}

struct HandleCloser {
  void operator()(sqlite3* db) const { sqlite3_close_v2(db); }
};
using Handle = std::unique_ptr<sqlite3, HandleCloser>;

Result<Handle> openReadOnlyHandle(const std::string& path, bool immutable) {
  sqlite3* raw = nullptr;
  const int rc = sqlite3_open_v2(readOnlyUri(path, immutable).c_str(), &raw,
                                 SQLITE_OPEN_READONLY | SQLITE_OPEN_URI | SQLITE_OPEN_FULLMUTEX, nullptr);
  Handle handle(raw);
  if (rc != SQLITE_OK) return fail(ErrorKind::Io, path + ": cannot open: " + errorText(raw, rc));
  sqlite3_extended_result_codes(raw, 1);
  return handle;
}

// The first column of the first row of `sql`, as text; nullopt and `rc` set on failure.
std::optional<std::string> queryText(sqlite3* db, const char* sql, int& rc) {
  sqlite3_stmt* stmt = nullptr;
  rc = sqlite3_prepare_v2(db, sql, -1, &stmt, nullptr);
  std::optional<std::string> value;
  if (rc == SQLITE_OK) {
    rc = sqlite3_step(stmt);
    if (rc == SQLITE_ROW) {
      const auto* text = reinterpret_cast<const char*>(sqlite3_column_text(stmt, 0));
      value = text ? text : "";
      rc = SQLITE_OK;
    }
  }
  if (rc != SQLITE_OK) rc = sqlite3_extended_errcode(db);
  sqlite3_finalize(stmt);
  return value;
}

// True if the database has a write-ahead log holding changes (then an immutable reader would miss
// them).
bool hasWalContent(const std::string& path) {
  std::error_code ec;
  const auto size = fs::file_size(path + "-wal", ec);
  return !ec && size > 0;
}

}  // namespace

bool sqliteWritable(const std::string& path) {
  const fs::path folder = fs::absolute(path).parent_path();
  return ::access(path.c_str(), W_OK) == 0 && ::access(folder.c_str(), W_OK) == 0;
}

Result<SqliteFileState> inspectSqlite(const std::string& path) {
  SqliteFileState state;
  int rc = SQLITE_OK;
  std::optional<std::string> version;
  for (const bool immutable : {false, true}) {
    if (immutable && hasWalContent(path)) break;
    state.immutable = immutable;
    auto handle = openReadOnlyHandle(path, immutable);
    if (!handle) return tl::unexpected(handle.error());
    sqlite3_busy_timeout(handle->get(), 5000);
    // One read transaction: the version, the mark and the tables come from one snapshot, so a file
    // another program is migrating at this moment is never seen half marked (closing the handle
    // ends the transaction).
    sqlite3_exec(handle->get(), "BEGIN", nullptr, nullptr, nullptr);
    version = queryText(handle->get(), "PRAGMA user_version", rc);
    if (!version) {
      const int primary = rc & 0xff;
      if (primary == SQLITE_NOTADB) return fail(path + ": not an Anatomy Tutor database (not a SQLite file)");
      if (primary == SQLITE_CORRUPT)
        return fail(ErrorKind::Io, path + ": the database is damaged (SQLite: " + errorText(handle->get(), rc) +
                                       "); it was left untouched — restore a backup or use another --db");
      const bool cannotIndex = primary == SQLITE_READONLY || primary == SQLITE_CANTOPEN || primary == SQLITE_IOERR;
      if (cannotIndex && !immutable) continue;
      return fail(ErrorKind::Io, path + ": cannot read the schema version: " + errorText(handle->get(), rc));
    }
    // quick_check: every page and index entry readable and consistent (O(size), not the full
    // integrity_check's cross-checks). A damaged file is refused before anything is written to it.
    auto check = queryText(handle->get(), "PRAGMA quick_check", rc);
    if (!check || *check != "ok") {
      const std::string problem = check ? *check : errorText(handle->get(), rc);
      return fail(ErrorKind::Io, path + ": the database is damaged (SQLite's quick_check: " +
                                     problem.substr(0, problem.find('\n')) +
                                     "); it was left untouched — restore a backup or use another --db");
    }
    // Whose file it is: our mark, or (files from before the mark) our tables; an empty schema is a
    // new file anyone may claim.
    auto application = queryText(handle->get(), "PRAGMA application_id", rc);
    auto tables = queryText(handle->get(),
                            "SELECT count(*) || ' ' || coalesce(sum(name IN ('datasets', 'courses', 'lessons')), 0) || ' ' || "
                            "coalesce(group_concat(name, ', '), '') FROM sqlite_master WHERE type = 'table' AND "
                            "name NOT LIKE 'sqlite_%'",
                            rc);
    if (!application || !tables)
      return fail(ErrorKind::Io, path + ": cannot read whose database it is: " + errorText(handle->get(), rc));
    long applicationId = 0;
    int tableCount = 0, oursCount = 0, names = 0;
    try {
      applicationId = std::stol(*application);
    } catch (const std::exception&) {
    }
    std::sscanf(tables->c_str(), "%d %d %n", &tableCount, &oursCount, &names);
    const std::string tableNames = tables->substr(std::min(std::size_t(names), tables->size()));
    state.marked = applicationId == kSqliteApplicationId;
    if (!state.marked) {
      const bool foreignMark = applicationId != 0;
      if (foreignMark || (tableCount > 0 && oursCount < 3)) {
        char id[32];
        std::snprintf(id, sizeof id, "0x%08lx", static_cast<unsigned long>(applicationId) & 0xffffffffUL);
        const std::string shown = tableNames.size() > 80 ? tableNames.substr(0, 80) + "…" : tableNames;
        return fail(path + ": not an Anatomy Tutor database (a SQLite file of another program: " +
                    (foreignMark ? "application id " + std::string(id) : "tables " + shown) +
                    "); it was left untouched — use another --db");
      }
    }
    break;
  }
  if (!version) return fail(ErrorKind::Io, path + ": cannot read the schema version");
  try {
    state.version = std::stoi(*version);
  } catch (const std::exception&) {
    return fail(ErrorKind::Io, path + ": unreadable schema version '" + *version + "'");
  }
  return state;
}

Result<std::unique_ptr<Connection>> openSqliteReadOnly(const std::string& path, const OpenOptions& options,
                                                       bool immutable) {
  auto handle = openReadOnlyHandle(path, immutable);
  if (!handle) return tl::unexpected(handle.error());
  sqlite3_busy_timeout(handle->get(), options.busyTimeoutMs);
  auto connection = std::make_unique<SqliteConnection>(handle->release(), path);
  if (auto s = connection->exec("PRAGMA foreign_keys = ON"); !s) return tl::unexpected(withContext(path, s.error()));
  return std::unique_ptr<Connection>(std::move(connection));
}

Result<std::unique_ptr<Connection>> openSqlite(const std::string& path, const OpenOptions& options) {
  sqlite3* raw = nullptr;
  const int flags = SQLITE_OPEN_READWRITE | (options.create ? SQLITE_OPEN_CREATE : 0) | SQLITE_OPEN_FULLMUTEX;
  const int rc = sqlite3_open_v2(path.c_str(), &raw, flags, nullptr);
  auto connection = std::make_unique<SqliteConnection>(raw, path);
  if (rc != SQLITE_OK) return fail(ErrorKind::Io, path + ": cannot open: " + errorText(raw, rc));
  sqlite3_extended_result_codes(raw, 1);
  sqlite3_busy_timeout(raw, options.busyTimeoutMs);

  // journal_mode needs the write lock briefly. SQLite returns SQLITE_BUSY at once, without the busy
  // handler, where waiting could deadlock (several programs opening one fresh file together), so
  // the switch is retried until the busy timeout has passed.
  {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(options.busyTimeoutMs);
    for (int attempt = 0;; ++attempt) {
      auto mode = connection->prepare("PRAGMA journal_mode = WAL");
      if (!mode) return tl::unexpected(mode.error());
      auto modeRow = (*mode)->step();
      if (modeRow) break;
      const int code = sqlite3_errcode(raw) & 0xFF;
      if ((code != SQLITE_BUSY && code != SQLITE_LOCKED) || std::chrono::steady_clock::now() >= deadline)
        return tl::unexpected(withContext(path + ": cannot switch to WAL", modeRow.error()));
      std::this_thread::sleep_for(std::chrono::milliseconds(5 + 5 * std::min(attempt, 9)));
    }
  }
  if (auto s = connection->exec("PRAGMA foreign_keys = ON; PRAGMA synchronous = FULL"); !s)
    return tl::unexpected(withContext(path, s.error()));
  return std::unique_ptr<Connection>(std::move(connection));
}

}  // namespace at::db::detail
