// Opening the program's store: a SQLite file (the embedded default) or a PostgreSQL database (a
// class server, `postgresql://…`), its schema brought to the current version on open.
//
// Outside db/ a database is only an opaque `Database&` handed to the stores (dataset_store.h,
// preset_store.h, study_store.h, course_store.h, exam_store.h, analytics_store.h) and the
// repositories (sql_repositories.h). The SQL wrapper — statements, transactions, migrations,
// the engines — is private to db/ (db/src/database.h); no other module can run SQL.
//
// Threads: a process keeps one connection (the app's learning session) and may use it from
// several threads; db/ serialises the calls and keeps each write transaction whole.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "core/error.h"

namespace at::db {

class Database;  // one open connection (db/src/database.h)

enum class Backend { Sqlite, Postgres };
const char* toString(Backend backend);  // "sqlite", "postgresql"

// True for a PostgreSQL connection URL (postgresql://… or postgres://…).
bool isPostgresUrl(std::string_view text);
// A PostgreSQL URL without its password (postgresql://user:secret@host/db → postgresql://user@host/db),
// for messages; anything else as it is.
std::string withoutPassword(const std::string& url);

struct OpenOptions {
  // Migrate to this schema version (tests build earlier versions with it); default: the newest.
  std::optional<int> targetVersion;
  // How long a statement waits for another connection's lock before SQLITE_BUSY.
  int busyTimeoutMs = 5000;
  // Create the file (and its folder) when missing. (A PostgreSQL database must exist.)
  bool create = true;
  // For commands that only read: a database this process cannot write (a read-only file, folder or
  // disk, or a disk too full for the WAL index) is opened read-only instead of failing, if it is
  // already at the target schema (SQLite files only). Its writes then fail with "the database is read-only".
  bool readOnlyIfNotWritable = false;
  // How long to wait for a PostgreSQL server to answer before giving up (libpq's minimum is 2 s).
  int connectTimeoutSeconds = 5;
};

// An open database, owned: closed when it dies. Move-only. It stands wherever a `Database&` is
// asked for (`db::saveStudy(connection, …)`).
class Connection {
 public:
  explicit Connection(std::unique_ptr<Database> database);
  ~Connection();
  Connection(Connection&&) noexcept;
  Connection& operator=(Connection&&) noexcept;
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  Database& get() const { return *database_; }
  operator Database&() const { return *database_; }
  // The file path, or the server URL without its password (for messages).
  const std::string& path() const;
  Backend backend() const;
  // True when opened read-only (OpenOptions::readOnlyIfNotWritable on a file it cannot write).
  bool readOnly() const;

 private:
  std::unique_ptr<Database> database_;
};

// The file or server a database was opened from (for messages), and its engine.
const std::string& pathOf(const Database& database);
Backend backendOf(const Database& database);

// The database the program uses when no --db is given:
// $XDG_DATA_HOME/anatomy-tutor/anatomy-tutor.db, else ~/.local/share/anatomy-tutor/anatomy-tutor.db.
Result<std::string> defaultDatabasePath();

// Opens `--db PATH` when given (a PostgreSQL URL, or a file whose folder exists), else the default
// path (creating its folder). A database written by a newer program, or a file that is not a
// SQLite database, is refused untouched.
Result<Connection> openDatabase(const std::optional<std::string>& path, const OpenOptions& options = {});

// For commands that only read (datasets, structures, wdt, render): the database at `dbPath` (the
// default database when nullopt) if it exists, nullopt if it does not — reading must not create a
// database as a side effect.
Result<std::optional<Connection>> openExistingDatabase(const std::optional<std::string>& dbPath);

}  // namespace at::db
