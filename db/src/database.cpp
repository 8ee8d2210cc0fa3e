// Database, Statement and Transaction over the SQLite C API; opening, pragmas and migrations.
#include "db/database.h"

#include <sqlite3.h>

#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
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

// The error of a failed SQLite call. What a user can act on — a full disk, a read-only or damaged
// database, a failing disk — is said in those words with the file named; anything else keeps
// SQLite's message.
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
  return tl::unexpected(sqliteError(db_, code, message));
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

Database::Database(Database&& other) noexcept
    : db_(other.db_), path_(std::move(other.path_)), readOnly_(other.readOnly_), writer_(std::move(other.writer_)) {
  other.db_ = nullptr;
}

Database& Database::operator=(Database&& other) noexcept {
  if (this != &other) {
    if (db_) sqlite3_close_v2(db_);
    db_ = other.db_;
    path_ = std::move(other.path_);
    readOnly_ = other.readOnly_;
    writer_ = std::move(other.writer_);
    other.db_ = nullptr;
  }
  return *this;
}

Result<Statement> Database::prepare(std::string_view sql) {
  sqlite3_stmt* stmt = nullptr;
  const int rc = sqlite3_prepare_v2(db_, sql.data(), int(sql.size()), &stmt, nullptr);
  if (rc != SQLITE_OK) {
    Error e = sqliteError(db_, sqlite3_extended_errcode(db_), errorText(db_, rc));
    if (e.message.rfind("SQL error: ", 0) == 0) e.message += " in: " + std::string(sql);
    return tl::unexpected(e);
  }
  return Statement(stmt, db_, std::string(sql));
}

Status Database::exec(std::string_view sql) {
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
  // Held across the retries too: the error code read below must be this thread's.
  std::unique_lock lock(*writer_);
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
  std::unique_lock lock(*db.writer_);
  auto status = db.exec(kind == Kind::Immediate ? "BEGIN IMMEDIATE" : "BEGIN");
  if (!status) return tl::unexpected(status.error());
  return Transaction(&db, std::move(lock));
}

Transaction::~Transaction() { rollback(); }

Transaction::Transaction(Transaction&& other) noexcept : db_(other.db_), lock_(std::move(other.lock_)) {
  other.db_ = nullptr;
}

Status Transaction::commit() {
  if (!db_) return fail("transaction already finished");
  auto status = db_->exec("COMMIT");
  if (!status) return status;  // still open: the destructor or rollback() ends it
  db_ = nullptr;
  if (lock_.owns_lock()) lock_.unlock();
  return {};
}

void Transaction::rollback() {
  if (!db_) return;
  if (!sqlite3_get_autocommit(db_->handle())) {
    sqlite3_exec(db_->handle(), "ROLLBACK", nullptr, nullptr, nullptr);
  }
  db_ = nullptr;
  if (lock_.owns_lock()) lock_.unlock();
}

// ---------------------------------------------------------------------------------------------
// Opening and migrating

namespace {

// How a connection opens the file: read-write, or read-only (nothing is ever written, not even the
// WAL index when `immutable`: then the file must not change while it is open).
struct ConnectionMode {
  bool readOnly = false;
  bool immutable = false;
};

// "file:/path?mode=ro": a URI, so that read-only connections can ask for `immutable`.
std::string uriOf(const std::string& path, const ConnectionMode& mode) {
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
  if (mode.readOnly) uri += mode.immutable ? "?mode=ro&immutable=1" : "?mode=ro";
  return uri;
}

struct ConnectionCloser {
  void operator()(sqlite3* db) const { sqlite3_close_v2(db); }
};
using Connection = std::unique_ptr<sqlite3, ConnectionCloser>;

Result<Connection> openConnection(const std::string& path, const ConnectionMode& mode, bool create) {
  sqlite3* raw = nullptr;
  const int flags = (mode.readOnly ? SQLITE_OPEN_READONLY : SQLITE_OPEN_READWRITE | (create ? SQLITE_OPEN_CREATE : 0)) |
                    SQLITE_OPEN_URI | SQLITE_OPEN_FULLMUTEX;
  const int rc = sqlite3_open_v2(uriOf(path, mode).c_str(), &raw, flags, nullptr);
  Connection connection(raw);
  if (rc != SQLITE_OK) return fail(ErrorKind::Io, path + ": cannot open: " + errorText(raw, rc));
  sqlite3_extended_result_codes(raw, 1);
  return connection;
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

// True if this process may write the file and create files beside it (the WAL and its index).
bool writable(const std::string& path) {
  const fs::path folder = fs::absolute(path).parent_path();
  return ::access(path.c_str(), W_OK) == 0 && ::access(folder.c_str(), W_OK) == 0;
}

struct FileState {
  int version = 0;
  ConnectionMode readMode;  // how a reader could open it
};

// Looks at an existing database without writing anything: its schema version and an integrity
// check (PRAGMA quick_check), through a read-only connection. A reader needs the WAL index beside
// the file; where it cannot be created (a read-only folder, a full disk) and no write-ahead log
// holds changes, the file is read as immutable instead.
Result<FileState> inspect(const std::string& path) {
  FileState state;
  state.readMode.readOnly = true;
  int rc = SQLITE_OK;
  std::optional<std::string> version;
  for (const bool immutable : {false, true}) {
    if (immutable && hasWalContent(path)) break;
    state.readMode.immutable = immutable;
    auto connection = openConnection(path, state.readMode, false);
    if (!connection) return tl::unexpected(connection.error());
    sqlite3_busy_timeout(connection->get(), 5000);
    version = queryText(connection->get(), "PRAGMA user_version", rc);
    if (!version) {
      const int primary = rc & 0xff;
      if (primary == SQLITE_NOTADB) return fail(path + ": not an Anatomy Tutor database (not a SQLite file)");
      if (primary == SQLITE_CORRUPT)
        return fail(ErrorKind::Io, path + ": the database is damaged (SQLite: " + errorText(connection->get(), rc) +
                                       "); it was left untouched — restore a backup or use another --db");
      const bool cannotIndex = primary == SQLITE_READONLY || primary == SQLITE_CANTOPEN || primary == SQLITE_IOERR;
      if (cannotIndex && !immutable) continue;
      return fail(ErrorKind::Io, path + ": cannot read the schema version: " + errorText(connection->get(), rc));
    }
    // quick_check: every page and index entry readable and consistent (O(size), not the full
    // integrity_check's cross-checks). A damaged file is refused before anything is written to it.
    auto check = queryText(connection->get(), "PRAGMA quick_check", rc);
    if (!check || *check != "ok") {
      const std::string problem = check ? *check : errorText(connection->get(), rc);
      return fail(ErrorKind::Io, path + ": the database is damaged (SQLite's quick_check: " +
                                     problem.substr(0, problem.find('\n')) +
                                     "); it was left untouched — restore a backup or use another --db");
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

// A schema version this program can migrate from: 0 (a new file) up to the newest it knows.
Status checkVersionKnown(const std::string& path, int version, int latest) {
  if (version > latest)
    return fail(ErrorKind::Conflict, path + ": written by a newer version of Anatomy Tutor (schema " + std::to_string(version) +
                                         ", this program knows up to " + std::to_string(latest) +
                                         "); update the program or use another --db");
  if (version < 0)
    return fail(ErrorKind::Invalid, path + ": schema version " + std::to_string(version) +
                                        " is not one any Anatomy Tutor writes (the file is damaged or not ours); it was "
                                        "left untouched — restore a backup or use another --db");
  return {};
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
      // Checked again here: another process may have written the version since the file was inspected.
      if (auto known = checkVersionKnown(d.path(), *version, int(all.size())); !known) return known;
      if (*version >= target) {
        done = true;
        return {};
      }
      const Migration& m = all[std::size_t(*version)];
      if (auto s = d.exec(m.sql); !s)
        return fail(s.error().kind, "migrating to schema version " + std::to_string(m.version) + " (" +
                                        std::string(m.summary) + "): " + s.error().message);
      return d.exec("PRAGMA user_version = " + std::to_string(m.version));
    });
    if (!status) {
      // The version checks already name the file.
      if (status.error().message.rfind(db.path() + ": ", 0) == 0) return tl::unexpected(status.error());
      return tl::unexpected(withContext(db.path(), status.error()));
    }
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
  if (exists && !fs::is_regular_file(path, ec)) return fail(path + ": not a database file (a folder or a device)");

  // Everything that refuses a file happens before it is opened for writing: journal_mode=WAL and
  // the migrations would already change it.
  FileState state;
  if (exists && fs::file_size(path, ec) > 0) {
    auto inspected = inspect(path);
    if (!inspected) return tl::unexpected(inspected.error());
    state = *inspected;
    if (auto known = checkVersionKnown(path, state.version, latest); !known) return tl::unexpected(known.error());
  }

  // A command that only reads opens a file it cannot write (a read-only file, folder or disk, or a
  // disk too full for the WAL index) read-only, as the inspection could.
  const bool readOnly = options.readOnlyIfNotWritable && exists && (!writable(path) || state.readMode.immutable);
  if (readOnly) {
    if (state.version != target)
      return fail(ErrorKind::Io, path + ": cannot be written and is at schema " + std::to_string(state.version) +
                                     ", this program needs " + std::to_string(target) +
                                     " — open it once with write access to upgrade it");
    auto connection = openConnection(path, state.readMode, false);
    if (!connection) return tl::unexpected(connection.error());
    Database db(connection->release(), path);
    db.readOnly_ = true;
    sqlite3_busy_timeout(db.db_, options.busyTimeoutMs);
    if (auto s = db.exec("PRAGMA foreign_keys = ON"); !s) return tl::unexpected(withContext(path, s.error()));
    return db;
  }

  auto connection = openConnection(path, ConnectionMode{}, options.create);
  if (!connection) return tl::unexpected(connection.error());
  Database db(connection->release(), path);
  sqlite3_busy_timeout(db.db_, options.busyTimeoutMs);

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
  // The default database's folder is made on first use; a path given with --db must lie in a
  // folder that exists (a mistyped value must not leave folders named after it).
  const fs::path parent = fs::path(chosen).parent_path();
  std::error_code ec;
  if (!parent.empty() && options.create && !path) {
    fs::create_directories(parent, ec);
    if (ec) return fail(ErrorKind::Io, parent.string() + ": cannot create the database folder: " + ec.message());
  } else if (!parent.empty() && !fs::is_directory(parent, ec)) {
    return fail(ErrorKind::NotFound, chosen + ": the folder " + parent.string() + " does not exist");
  }
  return Database::open(chosen, options);
}

}  // namespace at::db
