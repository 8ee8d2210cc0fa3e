// The SQLite store: one database file, opened in WAL mode with foreign keys on and a busy timeout,
// its schema brought to the current version by forward-only migrations (schema.h).
//
// Only db/ includes sqlite3.h; this header forward-declares the handle types. Every handle is owned
// by an RAII object: `Database` (the connection), `Statement` (a prepared statement), `Transaction`
// (rolled back when it dies uncommitted). All values reach SQL through bound parameters, never by
// pasting text into a statement.
//
// Threads: a process keeps one connection (the app's learning session). It may be used from
// several threads: SQLite serialises each call on it, and write transactions (writeTransaction,
// Transaction) take the connection's writer lock for their whole length, so one thread's
// transaction never takes in another thread's writes. A thread reading while another writes sees
// the uncommitted rows.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>

#include "core/error.h"

struct sqlite3;
struct sqlite3_stmt;

namespace at::db {

class Database;

// A prepared statement. Parameters are numbered from 1, result columns from 0 (as in SQLite).
// Move-only; finalized when it dies.
class Statement {
 public:
  Statement() = default;
  ~Statement();
  Statement(Statement&& other) noexcept;
  Statement& operator=(Statement&& other) noexcept;
  Statement(const Statement&) = delete;
  Statement& operator=(const Statement&) = delete;

  // Binding returns *this so calls chain; a bind error (index out of range) is kept and reported
  // by the next step()/run().
  Statement& bind(int index, std::int64_t value);
  Statement& bind(int index, int value) { return bind(index, std::int64_t(value)); }
  Statement& bind(int index, double value);
  Statement& bind(int index, std::string_view text);
  Statement& bind(int index, const char* text) { return bind(index, std::string_view(text)); }
  Statement& bind(int index, const std::string& text) { return bind(index, std::string_view(text)); }
  Statement& bindNull(int index);
  template <class T>
  Statement& bind(int index, const std::optional<T>& value) {
    return value ? bind(index, *value) : bindNull(index);
  }

  // Advances: true when a row is available, false when done; an error otherwise.
  Result<bool> step();
  // Steps to completion, ignoring rows (INSERT/UPDATE/DELETE).
  Status run();
  // Resets to run again; bindings are cleared.
  void reset();

  bool isNull(int column) const;
  std::int64_t int64(int column) const;
  int integer(int column) const { return int(int64(column)); }
  double real(int column) const;
  std::string text(int column) const;
  std::optional<std::string> optionalText(int column) const;
  std::optional<double> optionalReal(int column) const;

 private:
  friend class Database;
  Statement(sqlite3_stmt* stmt, sqlite3* db, std::string sql);
  void noteBind(int rc, int index);  // keeps the first bind error for step()
  sqlite3_stmt* stmt_ = nullptr;
  sqlite3* db_ = nullptr;
  std::string sql_;
  std::string bindError_;
};

struct OpenOptions {
  // Migrate to this schema version (tests build earlier versions with it); default: the newest.
  std::optional<int> targetVersion;
  // How long a statement waits for another connection's lock before SQLITE_BUSY.
  int busyTimeoutMs = 5000;
  // Create the file (and its folder) when missing.
  bool create = true;
  // For commands that only read: a database this process cannot write (a read-only file, folder or
  // disk, or a disk too full for the WAL index) is opened read-only instead of failing, if it is
  // already at the target schema. Its writes then fail with "the database is read-only".
  bool readOnlyIfNotWritable = false;
};

// An open connection. Move-only; closed when it dies.
class Database {
 public:
  // Opens (creating when allowed) the database at `path` and migrates it. A file written by a newer
  // version of the program (user_version above the newest known) is refused and left untouched,
  // as is a file that is not a SQLite database.
  static Result<Database> open(const std::string& path, const OpenOptions& options = {});

  Database() = default;
  ~Database();
  Database(Database&& other) noexcept;
  Database& operator=(Database&& other) noexcept;
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  const std::string& path() const { return path_; }
  bool isOpen() const { return db_ != nullptr; }
  // True when opened read-only (OpenOptions::readOnlyIfNotWritable on a file it cannot write).
  bool readOnly() const { return readOnly_; }

  Result<Statement> prepare(std::string_view sql);
  // Runs one or more statements without parameters (schema text, pragmas).
  Status exec(std::string_view sql);
  // PRAGMA user_version.
  Result<int> schemaVersion();
  std::int64_t lastInsertId() const;
  // Rows changed by the last INSERT/UPDATE/DELETE.
  int changes() const;

  // Runs `body` inside BEGIN IMMEDIATE … COMMIT. When another connection holds the write lock past
  // the busy timeout (SQLITE_BUSY), the whole transaction is rolled back and retried, so concurrent
  // writers lose nothing. Any other error from `body` rolls back and is returned.
  Status writeTransaction(const std::function<Status(Database&)>& body, int maxAttempts = 20);

  // The raw handle, for db/src only.
  sqlite3* handle() const { return db_; }

 private:
  friend class Transaction;
  Database(sqlite3* db, std::string path)
      : db_(db), path_(std::move(path)), writer_(std::make_unique<std::recursive_mutex>()) {}
  sqlite3* db_ = nullptr;
  std::string path_;
  bool readOnly_ = false;
  std::unique_ptr<std::recursive_mutex> writer_;  // held by the thread inside a write transaction
};

// BEGIN … COMMIT as an object: rolled back when it dies without commit().
class Transaction {
 public:
  enum class Kind { Deferred, Immediate };
  static Result<Transaction> begin(Database& db, Kind kind = Kind::Immediate);
  ~Transaction();
  Transaction(Transaction&& other) noexcept;
  Transaction& operator=(Transaction&&) = delete;
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;

  Status commit();
  void rollback();

 private:
  Transaction(Database* db, std::unique_lock<std::recursive_mutex> lock) : db_(db), lock_(std::move(lock)) {}
  Database* db_ = nullptr;  // null once committed or rolled back
  std::unique_lock<std::recursive_mutex> lock_;  // the connection's writer lock, released when finished
};

// The database the program uses when no --db is given:
// $XDG_DATA_HOME/anatomy-tutor/anatomy-tutor.db, else ~/.local/share/anatomy-tutor/anatomy-tutor.db.
Result<std::string> defaultDatabasePath();

// Opens `--db PATH` when given (its folder must exist), else the default path (creating its folder).
Result<Database> openDatabase(const std::optional<std::string>& path, const OpenOptions& options = {});

}  // namespace at::db
