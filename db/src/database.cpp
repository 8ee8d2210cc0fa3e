// Database, Statement and Transaction over the SQLite C API; opening, pragmas and migrations.
#include "db/database.h"

#include <sqlite3.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <thread>

#include "db/schema.h"

namespace at::db {

namespace fs = std::filesystem;

namespace {

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

}  // namespace

// ---------------------------------------------------------------------------------------------
// Statement

Statement::Statement(sqlite3_stmt* stmt, sqlite3* db, std::string sql)
    : stmt_(stmt), db_(db), sql_(std::move(sql)) {}

Statement::~Statement() {
  if (stmt_) sqlite3_finalize(stmt_);
}

Statement::Statement(Statement&& other) noexcept
    : stmt_(other.stmt_), db_(other.db_), sql_(std::move(other.sql_)), bindError_(std::move(other.bindError_)) {
  other.stmt_ = nullptr;
  other.db_ = nullptr;
}

Statement& Statement::operator=(Statement&& other) noexcept {
  if (this != &other) {
    if (stmt_) sqlite3_finalize(stmt_);
    stmt_ = other.stmt_;
    db_ = other.db_;
    sql_ = std::move(other.sql_);
    bindError_ = std::move(other.bindError_);
    other.stmt_ = nullptr;
    other.db_ = nullptr;
  }
  return *this;
}

void Statement::noteBind(int rc, int index) {
  if (rc != SQLITE_OK && bindError_.empty())
    bindError_ = "binding parameter " + std::to_string(index) + ": " + errorText(db_, rc);
}

Statement& Statement::bind(int index, std::int64_t value) {
  noteBind(sqlite3_bind_int64(stmt_, index, value), index);
  return *this;
}

Statement& Statement::bind(int index, double value) {
  noteBind(sqlite3_bind_double(stmt_, index, value), index);
  return *this;
}

Statement& Statement::bind(int index, std::string_view text) {
  // SQLITE_TRANSIENT: SQLite copies the bytes, so temporaries are safe to pass.
  noteBind(sqlite3_bind_text64(stmt_, index, text.data(), text.size(), SQLITE_TRANSIENT, SQLITE_UTF8), index);
  return *this;
}

Statement& Statement::bindNull(int index) {
  noteBind(sqlite3_bind_null(stmt_, index), index);
  return *this;
}

Result<bool> Statement::step() {
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

Status Statement::run() {
  while (true) {
    auto row = step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) return {};
  }
}

void Statement::reset() {
  sqlite3_reset(stmt_);
  sqlite3_clear_bindings(stmt_);
  bindError_.clear();
}

bool Statement::isNull(int column) const { return sqlite3_column_type(stmt_, column) == SQLITE_NULL; }
std::int64_t Statement::int64(int column) const { return sqlite3_column_int64(stmt_, column); }
double Statement::real(int column) const { return sqlite3_column_double(stmt_, column); }

std::string Statement::text(int column) const {
  const auto* p = reinterpret_cast<const char*>(sqlite3_column_text(stmt_, column));
  const int n = sqlite3_column_bytes(stmt_, column);
  return p ? std::string(p, std::size_t(n)) : std::string();
}

std::optional<std::string> Statement::optionalText(int column) const {
  if (isNull(column)) return std::nullopt;
  return text(column);
}

std::optional<double> Statement::optionalReal(int column) const {
  if (isNull(column)) return std::nullopt;
  return real(column);
}

// ---------------------------------------------------------------------------------------------
// Database

Database::~Database() {
  if (db_) sqlite3_close_v2(db_);
}

Database::Database(Database&& other) noexcept : db_(other.db_), path_(std::move(other.path_)) { other.db_ = nullptr; }

Database& Database::operator=(Database&& other) noexcept {
  if (this != &other) {
    if (db_) sqlite3_close_v2(db_);
    db_ = other.db_;
    path_ = std::move(other.path_);
    other.db_ = nullptr;
  }
  return *this;
}

Result<Statement> Database::prepare(std::string_view sql) {
  sqlite3_stmt* stmt = nullptr;
  const int rc = sqlite3_prepare_v2(db_, sql.data(), int(sql.size()), &stmt, nullptr);
  if (rc != SQLITE_OK) return fail(kindOf(sqlite3_extended_errcode(db_)), "SQL error: " + errorText(db_, rc) + " in: " + std::string(sql));
  return Statement(stmt, db_, std::string(sql));
}

Status Database::exec(std::string_view sql) {
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

Result<int> Database::schemaVersion() {
  auto stmt = prepare("PRAGMA user_version");
  if (!stmt) return tl::unexpected(stmt.error());
  auto row = stmt->step();
  if (!row) return tl::unexpected(row.error());
  return *row ? stmt->integer(0) : 0;
}

std::int64_t Database::lastInsertId() const { return sqlite3_last_insert_rowid(db_); }
int Database::changes() const { return sqlite3_changes(db_); }

Status Database::writeTransaction(const std::function<Status(Database&)>& body, int maxAttempts) {
  std::minstd_rand jitter(std::random_device{}());
  Error last{ErrorKind::Io, "no attempt made"};
  for (int attempt = 0; attempt < maxAttempts; ++attempt) {
    auto tx = Transaction::begin(*this, Transaction::Kind::Immediate);
    if (tx) {
      Status done = body(*this);
      if (done) {
        done = tx->commit();
        if (done) return {};
      }
      last = done.error();
      // The error code is the connection's most recent one: decide before rolling back.
      const bool busy = isBusyCode(sqlite3_extended_errcode(db_));
      tx->rollback();
      if (!busy) return tl::unexpected(last);
    } else {
      last = tx.error();
      if (!isBusyCode(sqlite3_extended_errcode(db_))) return tl::unexpected(last);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5 + int(jitter() % 50)));
  }
  return fail(ErrorKind::Unavailable, "still locked by another process after " + std::to_string(maxAttempts) +
              " attempts: " + last.message);
}

// ---------------------------------------------------------------------------------------------
// Transaction

Result<Transaction> Transaction::begin(Database& db, Kind kind) {
  auto status = db.exec(kind == Kind::Immediate ? "BEGIN IMMEDIATE" : "BEGIN");
  if (!status) return tl::unexpected(status.error());
  return Transaction(&db);
}

Transaction::~Transaction() { rollback(); }

Transaction::Transaction(Transaction&& other) noexcept : db_(other.db_) { other.db_ = nullptr; }

Status Transaction::commit() {
  if (!db_) return fail("transaction already finished");
  auto status = db_->exec("COMMIT");
  if (!status) return status;  // still open: the destructor or rollback() ends it
  db_ = nullptr;
  return {};
}

void Transaction::rollback() {
  if (!db_) return;
  if (!sqlite3_get_autocommit(db_->handle())) {
    sqlite3_exec(db_->handle(), "ROLLBACK", nullptr, nullptr, nullptr);
  }
  db_ = nullptr;
}

// ---------------------------------------------------------------------------------------------
// Opening and migrating

namespace {

// Reads user_version without writing anything: a read-only connection, no pragmas that write.
// Returns 0 for a missing or empty file.
Result<int> peekVersion(const std::string& path) {
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

Status migrate(Database& db, int target) {
  const auto& all = migrations();
  while (true) {
    // Each step re-reads the version inside its own write transaction, so two processes opening
    // a fresh file at once apply every migration exactly once.
    bool done = false;
    auto status = db.writeTransaction([&](Database& d) -> Status {
      auto version = d.schemaVersion();
      if (!version) return tl::unexpected(version.error());
      if (*version >= target) {
        done = true;
        return {};
      }
      const Migration& m = all[std::size_t(*version)];
      if (auto s = d.exec(m.sql); !s)
        return fail("migrating to schema version " + std::to_string(m.version) + " (" + std::string(m.summary) +
                    "): " + s.error().message);
      return d.exec("PRAGMA user_version = " + std::to_string(m.version));
    });
    if (!status) return tl::unexpected(withContext(db.path(), status.error()));
    if (done) return {};
  }
}

}  // namespace

Result<Database> Database::open(const std::string& path, const OpenOptions& options) {
  const int latest = latestSchemaVersion();
  const int target = options.targetVersion.value_or(latest);
  if (target < 0 || target > latest)
    return fail("schema version " + std::to_string(target) + " is not known (newest: " + std::to_string(latest) + ")");

  std::error_code ec;
  const bool exists = fs::exists(path, ec);
  if (!exists && !options.create) return fail(ErrorKind::NotFound, path + ": no such database");

  // Refuse newer files before opening for writing: journal_mode=WAL would already change the file.
  auto existing = peekVersion(path);
  if (!existing) return tl::unexpected(existing.error());
  if (*existing > latest)
    return fail(path + ": written by a newer version of Anatomy Tutor (schema " + std::to_string(*existing) +
                ", this program knows up to " + std::to_string(latest) + "); update the program or use another --db");

  sqlite3* raw = nullptr;
  const int flags = SQLITE_OPEN_READWRITE | (options.create ? SQLITE_OPEN_CREATE : 0) | SQLITE_OPEN_NOMUTEX;
  const int rc = sqlite3_open_v2(path.c_str(), &raw, flags, nullptr);
  Database db(raw, path);
  if (rc != SQLITE_OK) return fail(ErrorKind::Io, path + ": cannot open: " + errorText(raw, rc));
  sqlite3_extended_result_codes(raw, 1);
  sqlite3_busy_timeout(raw, options.busyTimeoutMs);

  // journal_mode needs the write lock briefly; busy_timeout covers a concurrent opener.
  {
    auto mode = db.prepare("PRAGMA journal_mode = WAL");
    if (!mode) return tl::unexpected(mode.error());
    auto modeRow = mode->step();
    if (!modeRow) return tl::unexpected(withContext(path + ": cannot switch to WAL", modeRow.error()));
  }
  if (auto s = db.exec("PRAGMA foreign_keys = ON; PRAGMA synchronous = FULL"); !s)
    return tl::unexpected(withContext(path, s.error()));

  if (auto s = migrate(db, target); !s) return tl::unexpected(s.error());
  return db;
}

Result<std::string> defaultDatabasePath() {
  fs::path base;
  if (const char* xdg = std::getenv("XDG_DATA_HOME"); xdg && *xdg && fs::path(xdg).is_absolute()) {
    base = xdg;
  } else if (const char* home = std::getenv("HOME"); home && *home) {
    base = fs::path(home) / ".local" / "share";
  } else {
    return fail("neither XDG_DATA_HOME nor HOME is set: pass --db PATH");
  }
  return (base / "anatomy-tutor" / "anatomy-tutor.db").string();
}

Result<Database> openDatabase(const std::optional<std::string>& path, const OpenOptions& options) {
  std::string chosen;
  if (path) {
    chosen = *path;
  } else {
    auto def = defaultDatabasePath();
    if (!def) return tl::unexpected(def.error());
    chosen = *def;
  }
  const fs::path parent = fs::path(chosen).parent_path();
  if (!parent.empty() && options.create) {
    std::error_code ec;
    fs::create_directories(parent, ec);
    if (ec) return fail(parent.string() + ": cannot create the database folder: " + ec.message());
  }
  return Database::open(chosen, options);
}

}  // namespace at::db
