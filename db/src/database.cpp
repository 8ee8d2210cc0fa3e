// Database, Statement and Transaction over the engines of backend.h; opening and migrating; the
// public Connection that owns a Database.
#include "database.h"
#include "db/all_or_nothing.h"

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <thread>

#include "backend.h"
#include "schema.h"

namespace at::db {

namespace fs = std::filesystem;

const char* toString(Backend backend) { return backend == Backend::Postgres ? "postgresql" : "sqlite"; }

bool isPostgresUrl(std::string_view text) {
  return text.rfind("postgresql://", 0) == 0 || text.rfind("postgres://", 0) == 0;
}

// ---------------------------------------------------------------------------------------------
// Statement

Statement::Statement() = default;
Statement::~Statement() = default;
Statement::Statement(Statement&& other) noexcept = default;
Statement& Statement::operator=(Statement&& other) noexcept = default;
Statement::Statement(std::unique_ptr<detail::Cursor> cursor, std::string sql)
    : cursor_(std::move(cursor)), sql_(std::move(sql)) {}

Statement& Statement::bind(int index, std::int64_t value) {
  cursor_->bindInt(index, value);
  return *this;
}

Statement& Statement::bind(int index, double value) {
  cursor_->bindReal(index, value);
  return *this;
}

Statement& Statement::bind(int index, std::string_view text) {
  cursor_->bindText(index, text);
  return *this;
}

Statement& Statement::bindNull(int index) {
  cursor_->bindNull(index);
  return *this;
}

Result<bool> Statement::step() { return cursor_->step(); }

Status Statement::run() {
  while (true) {
    auto row = step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) return {};
  }
}

Result<std::int64_t> Statement::insertReturningId() {
  auto row = step();
  if (!row) return tl::unexpected(row.error());
  if (!*row) return fail(ErrorKind::Io, "SQL: the insert returned no id: " + sql_);
  const std::int64_t id = int64(0);
  // Finish the statement so that it is complete before the transaction commits.
  if (auto done = run(); !done) return tl::unexpected(done.error());
  return id;
}

void Statement::reset() { cursor_->reset(); }
bool Statement::isNull(int column) const { return cursor_->isNull(column); }
std::int64_t Statement::int64(int column) const { return cursor_->int64(column); }
double Statement::real(int column) const { return cursor_->real(column); }
std::string Statement::text(int column) const { return cursor_->text(column); }

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

Database::Database() = default;
Database::~Database() = default;
Database::Database(Database&& other) noexcept = default;
Database& Database::operator=(Database&& other) noexcept = default;
Database::Database(std::unique_ptr<detail::Connection> connection)
    : connection_(std::move(connection)), writer_(std::make_unique<std::recursive_mutex>()) {}

const std::string& Database::path() const {
  static const std::string none;
  return connection_ ? connection_->name() : none;
}

Backend Database::backend() const { return connection_->backend(); }

Result<Statement> Database::prepare(std::string_view sql) {
  auto cursor = connection_->prepare(sql);
  if (!cursor) return tl::unexpected(cursor.error());
  return Statement(std::move(*cursor), std::string(sql));
}

Status Database::exec(std::string_view sql) { return connection_->exec(sql); }
Result<int> Database::schemaVersion() { return connection_->schemaVersion(); }
int Database::changes() const { return connection_->changes(); }

Status Database::writeTransaction(const std::function<Status(Database&)>& body, int maxAttempts) {
  return keyedWriteTransaction("", body, true, maxAttempts);
}

Status Database::keyedWriteTransaction(const std::string& key, const std::function<Status(Database&)>& body,
                                       bool programWide, int maxAttempts) {
  const bool keyed = !key.empty() && backend() == Backend::Postgres;
  const auto kind = keyed && !programWide ? Transaction::Kind::Deferred : Transaction::Kind::Immediate;
  // Held across the retries too: the failure examined below must be this thread's.
  std::unique_lock lock(*writer_);
  // Inside this thread's own write transaction (the lock is recursive; another thread's would
  // have kept us waiting above): join it, so that its caller commits or rolls back everything.
  if (writeDepth_ > 0) return body(*this);
  std::minstd_rand jitter(std::random_device{}());
  Error last{ErrorKind::Io, "no attempt made"};
  for (int attempt = 0; attempt < maxAttempts; ++attempt) {
    auto tx = Transaction::begin(*this, kind);
    if (tx && keyed) {
      // Transaction-scoped, in the two-key space (apart from the writer lock's one key).
      auto keyLock = prepare("SELECT pg_advisory_xact_lock(1, hashtext(?1))");
      Status locked = keyLock ? Status{} : Status(tl::unexpected(keyLock.error()));
      if (keyLock) {
        keyLock->bind(1, key);
        if (auto row = keyLock->step(); !row) locked = tl::unexpected(row.error());
      }
      if (!locked) {
        last = locked.error();
        const bool contention = connection_->lastFailureWasContention();
        tx->rollback();
        if (!contention) return tl::unexpected(last);
        std::this_thread::sleep_for(std::chrono::milliseconds(5 + int(jitter() % 50)));
        continue;
      }
    }
    if (tx) {
      ++writeDepth_;
      Status done = [&] {
        struct Leave {
          int& depth;
          ~Leave() { --depth; }
        } leave{writeDepth_};
        return body(*this);
      }();
      if (done) {
        done = tx->commit();
        if (done) return {};
      }
      last = done.error();
      // Decide from the connection's most recent failure, before rolling back.
      const bool contention = connection_->lastFailureWasContention();
      tx->rollback();
      if (!contention) return tl::unexpected(last);
    } else {
      last = tx.error();
      if (!connection_->lastFailureWasContention()) return tl::unexpected(last);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5 + int(jitter() % 50)));
  }
  return fail(ErrorKind::Unavailable, "still locked by another writer after " + std::to_string(maxAttempts) +
                                          " attempts: " + last.message);
}

// ---------------------------------------------------------------------------------------------
// Transaction

Result<Transaction> Transaction::begin(Database& db, Kind kind) {
  std::unique_lock lock(*db.writer_);
  auto status = db.connection_->begin(kind == Kind::Immediate);
  if (!status) return tl::unexpected(status.error());
  return Transaction(&db, std::move(lock));
}

Transaction::~Transaction() { rollback(); }

Transaction::Transaction(Transaction&& other) noexcept : db_(other.db_), lock_(std::move(other.lock_)) {
  other.db_ = nullptr;
}

Status Transaction::commit() {
  if (!db_) return fail("transaction already finished");
  auto status = db_->connection_->commit();
  if (!status) return status;  // still open: the destructor or rollback() ends it
  db_ = nullptr;
  if (lock_.owns_lock()) lock_.unlock();
  return {};
}

void Transaction::rollback() {
  if (!db_) return;
  if (db_->connection_->inTransaction()) db_->connection_->rollback();
  db_ = nullptr;
  if (lock_.owns_lock()) lock_.unlock();
}

// ---------------------------------------------------------------------------------------------
// Opening and migrating

namespace {

// A schema version this program can migrate from: 0 (a new database) up to the newest it knows.
// Anything else — a newer program's database, or a negative version in a damaged or hostile file —
// is refused before anything is written to it.
Status checkVersionKnown(const std::string& name, int version, int latest) {
  if (version > latest)
    return fail(ErrorKind::Conflict, name + ": written by a newer version of Anatomy Tutor (schema " +
                                         std::to_string(version) + ", this program knows up to " +
                                         std::to_string(latest) + "); update the program or use another --db");
  if (version < 0)
    return fail(ErrorKind::Invalid, name + ": schema version " + std::to_string(version) +
                                        " is not one any Anatomy Tutor writes (the database is damaged or not ours); "
                                        "it was left untouched — restore a backup or use another --db");
  return {};
}

}  // namespace

Status Database::migrate(int target) {
  const auto& all = migrations();
  const Backend engine = backend();
  while (true) {
    // Each step re-reads the version inside its own write transaction, so two processes opening
    // a fresh database at once apply every migration exactly once.
    bool done = false;
    auto status = writeTransaction([&](Database& d) -> Status {
      auto version = d.schemaVersion();
      if (!version) return tl::unexpected(version.error());
      // Checked again here: another process may have written the version since it was first read.
      if (auto known = checkVersionKnown(d.path(), *version, int(all.size())); !known) return known;
      if (*version >= target) {
        done = true;
        return {};
      }
      const Migration& m = all[std::size_t(*version)];
      // A SQLite file is marked as ours in the same transaction that creates its first tables, so
      // no other program opening it meanwhile sees our tables without our mark (and refuses the
      // file as another program's).
      if (engine == Backend::Sqlite)
        if (auto s = d.exec("PRAGMA application_id = " + std::to_string(detail::kSqliteApplicationId)); !s) return s;
      if (auto s = d.exec(migrationSql(m, engine)); !s)
        return fail(s.error().kind, "migrating to schema version " + std::to_string(m.version) + " (" +
                                        std::string(m.summary) + "): " + s.error().message);
      return d.connection_->setSchemaVersion(m.version);
    });
    if (!status) {
      // The version checks already name the database.
      if (status.error().message.rfind(path() + ": ", 0) == 0) return tl::unexpected(status.error());
      return tl::unexpected(withContext(path(), status.error()));
    }
    if (done) return {};
  }
}

Result<Database> Database::open(const std::string& location, const OpenOptions& options) {
  const int latest = latestSchemaVersion();
  const int target = options.targetVersion.value_or(latest);
  if (target < 0 || target > latest)
    return fail("schema version " + std::to_string(target) + " is not known (newest: " + std::to_string(latest) + ")");

  std::unique_ptr<detail::Connection> connection;
  bool readOnly = false;
  bool sqliteMarked = false;
  if (isPostgresUrl(location)) {
    auto pg = detail::openPostgres(location, options);
    if (!pg) return tl::unexpected(pg.error());
    connection = std::move(*pg);
    auto existing = connection->schemaVersion();
    if (!existing) return tl::unexpected(withContext(connection->name(), existing.error()));
    if (auto known = checkVersionKnown(connection->name(), *existing, latest); !known)
      return tl::unexpected(known.error());
  } else {
    std::error_code ec;
    const bool exists = fs::exists(location, ec);
    if (!exists && !options.create) return fail(ErrorKind::NotFound, location + ": no such database");
    if (exists && !fs::is_regular_file(location, ec))
      return fail(location + ": not a database file (a folder or a device)");
    // Everything that refuses a file happens before it is opened for writing: journal_mode=WAL and
    // the migrations would already change it.
    detail::SqliteFileState state;
    if (exists && fs::file_size(location, ec) > 0) {
      auto inspected = detail::inspectSqlite(location);
      if (!inspected) return tl::unexpected(inspected.error());
      state = *inspected;
      sqliteMarked = state.marked;
      if (auto known = checkVersionKnown(location, state.version, latest); !known) return tl::unexpected(known.error());
    }
    // A command that only reads opens a file it cannot write (a read-only file, folder or disk, or
    // a disk too full for the WAL index) read-only, as the inspection could.
    readOnly = options.readOnlyIfNotWritable && exists && (!detail::sqliteWritable(location) || state.immutable);
    if (readOnly && state.version != target)
      return fail(ErrorKind::Io, location + ": cannot be written and is at schema " + std::to_string(state.version) +
                                     ", this program needs " + std::to_string(target) +
                                     " — open it once with write access to upgrade it");
    auto sqlite = readOnly ? detail::openSqliteReadOnly(location, options, state.immutable)
                           : detail::openSqlite(location, options);
    if (!sqlite) return tl::unexpected(sqlite.error());
    connection = std::move(*sqlite);
  }
  Database db(std::move(connection));
  db.readOnly_ = readOnly;
  if (readOnly) return db;
  if (auto s = db.migrate(target); !s) return tl::unexpected(s.error());
  // Mark the file as ours once (new files, and ours from before the mark), so that it is never
  // mistaken for another program's and another program's never for ours.
  if (db.backend() == Backend::Sqlite && !sqliteMarked)
    if (auto s = db.exec("PRAGMA application_id = " + std::to_string(detail::kSqliteApplicationId)); !s)
      return tl::unexpected(withContext(location, s.error()));
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

namespace {
// `--db` when given, else the default database's path.
Result<std::string> chosenLocation(const std::optional<std::string>& path) {
  if (path) return *path;
  return defaultDatabasePath();
}

Result<Connection> owned(Result<Database> database) {
  if (!database) return tl::unexpected(database.error());
  return Connection(std::make_unique<Database>(std::move(*database)));
}
}  // namespace

Connection::Connection(std::unique_ptr<Database> database) : database_(std::move(database)) {}
Connection::~Connection() = default;
Connection::Connection(Connection&&) noexcept = default;
Connection& Connection::operator=(Connection&&) noexcept = default;
const std::string& Connection::path() const { return database_->path(); }
Backend Connection::backend() const { return database_->backend(); }
bool Connection::readOnly() const { return database_->readOnly(); }
const std::string& pathOf(const Database& database) { return database.path(); }
Backend backendOf(const Database& database) { return database.backend(); }

Status writeAllOrNothing(Database& database, const std::function<Status()>& body) {
  return database.writeTransaction([&](Database&) { return body(); });
}

Result<Connection> openDatabase(const std::optional<std::string>& path, const OpenOptions& options) {
  if (path && isPostgresUrl(*path)) return owned(Database::open(*path, options));
  auto location = chosenLocation(path);
  if (!location) return tl::unexpected(location.error());
  const std::string& chosen = *location;
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
  return owned(Database::open(chosen, options));
}

Result<std::optional<Connection>> openExistingDatabase(const std::optional<std::string>& dbPath) {
  auto path = chosenLocation(dbPath);
  if (!path) return tl::unexpected(path.error());
  std::error_code ec;
  if (!isPostgresUrl(*path) && !fs::exists(*path, ec)) return std::optional<Connection>{};
  OpenOptions options;
  options.create = false;
  options.readOnlyIfNotWritable = true;
  auto connection = owned(Database::open(*path, options));
  if (!connection) return tl::unexpected(connection.error());
  return std::optional<Connection>(std::move(*connection));
}

}  // namespace at::db
