// The two storage engines behind db::Database, private to db/: SQLite (an embedded file) and
// PostgreSQL (a class server reached through libpq). Repositories write one SQL text for both,
// with parameters numbered ?1, ?2, … (the PostgreSQL connection renumbers them $1, $2, …) and
// without engine-only functions; the few differences (schema types, the schema version's home,
// how a write transaction locks) live in the connections.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "core/error.h"
#include "database.h"

namespace at::db::detail {

// One prepared statement being bound, run and read. Parameters are numbered from 1, columns
// from 0. A bind error is reported by the next step().
class Cursor {
 public:
  virtual ~Cursor() = default;
  virtual void bindInt(int index, std::int64_t value) = 0;
  virtual void bindReal(int index, double value) = 0;
  virtual void bindText(int index, std::string_view value) = 0;
  virtual void bindNull(int index) = 0;
  // True when a row is available, false when done.
  virtual Result<bool> step() = 0;
  // Ready to run again with no bindings.
  virtual void reset() = 0;
  virtual bool isNull(int column) const = 0;
  virtual std::int64_t int64(int column) const = 0;
  virtual double real(int column) const = 0;
  virtual std::string text(int column) const = 0;
};

class Connection {
 public:
  virtual ~Connection() = default;
  virtual Backend backend() const = 0;
  // What messages call the database: the file path, or the server URL without its password.
  virtual const std::string& name() const = 0;
  virtual Result<std::unique_ptr<Cursor>> prepare(std::string_view sql) = 0;
  // One or more statements without parameters.
  virtual Status exec(std::string_view sql) = 0;
  // Rows changed by the last INSERT/UPDATE/DELETE.
  virtual int changes() const = 0;
  // Starts a transaction. A write transaction is the only writer until it ends (SQLite: BEGIN
  // IMMEDIATE; PostgreSQL: a transaction-scoped advisory lock all writers of the program take).
  virtual Status begin(bool write) = 0;
  virtual Status commit() = 0;
  virtual void rollback() = 0;
  virtual bool inTransaction() const = 0;
  // True when the last failure was another writer holding a lock (SQLITE_BUSY, a PostgreSQL
  // serialization failure or deadlock): the whole transaction may be retried.
  virtual bool lastFailureWasContention() const = 0;
  // The schema version (0 for an empty database) and setting it inside a migration.
  virtual Result<int> schemaVersion() = 0;
  virtual Status setSchemaVersion(int version) = 0;
};

// Opens the SQLite file at `path` (WAL, foreign keys on, FULL sync, busy timeout).
Result<std::unique_ptr<Connection>> openSqlite(const std::string& path, const OpenOptions& options);

// What opening an existing SQLite file may rely on, learnt without writing to it.
struct SqliteFileState {
  int version = 0;         // PRAGMA user_version, as stored (may be anything in a hostile file)
  bool immutable = false;  // readable only as immutable: no WAL index can be made beside it
  bool marked = false;     // PRAGMA application_id is ours (kSqliteApplicationId)
};
// PRAGMA application_id of every Anatomy Tutor SQLite file ("ATut"), set on the first open that
// may write. Files from before it are recognised by their tables.
inline constexpr int kSqliteApplicationId = 0x41547574;
// Reads an existing, non-empty SQLite file's schema version and checks every page (PRAGMA
// quick_check) through a read-only connection. A reader needs the WAL index beside the file; where
// it cannot be made (a read-only folder, a full disk) and no write-ahead log holds changes, the
// file is read as immutable. A damaged file or one that is not SQLite is an error naming it, and so
// is a SQLite file of another program (another application_id, or unmarked with tables that are not
// ours): those are refused before anything is written, so they stay byte-identical.
Result<SqliteFileState> inspectSqlite(const std::string& path);
// Opens the SQLite file read-only (immutable as inspectSqlite found it), foreign keys on: for
// commands that only read a file this process cannot write.
Result<std::unique_ptr<Connection>> openSqliteReadOnly(const std::string& path, const OpenOptions& options,
                                                       bool immutable);
// True if this process may write the file and create files beside it (the WAL and its index).
bool sqliteWritable(const std::string& path);
// Connects to the PostgreSQL server at `url` (postgresql://… or postgres://…).
Result<std::unique_ptr<Connection>> openPostgres(const std::string& url, const OpenOptions& options);

// `?N` placeholders as PostgreSQL's `$N`, leaving quoted text alone.
std::string postgresPlaceholders(std::string_view sql);

}  // namespace at::db::detail
