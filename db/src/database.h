// The SQL wrapper, private to db/: `Database` (one connection), `Statement` (a prepared
// statement), `Transaction` (rolled back when it dies uncommitted) over the engines of backend.h
// (SQLite and PostgreSQL; only db/ includes sqlite3.h or libpq-fe.h). Both engines run the same
// repositories and the same SQL. Every value reaches SQL through bound parameters, never by
// pasting text into a statement. Outside db/ (connection.h) a Database is opaque.
//
// Threads: each call is serialised on the connection, and write transactions (writeTransaction,
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
#include "db/connection.h"

namespace at::db {

namespace detail {
class Cursor;
class Connection;
}  // namespace detail

// A prepared statement. Parameters are numbered from 1 and written ?1, ?2, … in the SQL text;
// result columns are numbered from 0. Move-only; finalized when it dies.
class Statement {
 public:
  Statement();
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
  // Runs an INSERT … RETURNING id and gives the id.
  Result<std::int64_t> insertReturningId();
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
  Statement(std::unique_ptr<detail::Cursor> cursor, std::string sql);
  std::unique_ptr<detail::Cursor> cursor_;
  std::string sql_;
};

// An open connection. Move-only; closed when it dies.
class Database {
 public:
  // Opens the database `location` names and migrates it: a PostgreSQL URL connects to that
  // server's database (which must exist; its tables are created), anything else is a SQLite file,
  // created when allowed. A database written by a newer version of the program (schema above the
  // newest known) is refused and left untouched, as is a file that is not a SQLite database.
  static Result<Database> open(const std::string& location, const OpenOptions& options = {});

  Database();
  ~Database();
  Database(Database&& other) noexcept;
  Database& operator=(Database&& other) noexcept;
  Database(const Database&) = delete;
  Database& operator=(const Database&) = delete;

  // The file path, or the server URL without its password (for messages).
  const std::string& path() const;
  bool isOpen() const { return connection_ != nullptr; }
  Backend backend() const;
  // True when opened read-only (OpenOptions::readOnlyIfNotWritable on a file it cannot write).
  bool readOnly() const { return readOnly_; }

  Result<Statement> prepare(std::string_view sql);
  // Runs one or more statements without parameters (schema text).
  Status exec(std::string_view sql);
  // The schema version (SQLite: PRAGMA user_version; PostgreSQL: the at_schema_version table).
  Result<int> schemaVersion();
  // Rows changed by the last INSERT/UPDATE/DELETE.
  int changes() const;

  // Runs `body` inside a write transaction (SQLite: BEGIN IMMEDIATE; PostgreSQL: BEGIN and the
  // program's writer lock). When another connection holds the lock past the busy timeout, or the
  // server reports a serialization failure, the whole transaction is rolled back and retried, so
  // concurrent writers lose nothing. Any other error from `body` rolls back and is returned.
  // Called from inside another writeTransaction's body on the same thread, it joins that one.
  Status writeTransaction(const std::function<Status(Database&)>& body, int maxAttempts = 20);
  // The same for writes confined to what `key` names (one study participant's rows): on
  // PostgreSQL the transaction takes a lock on `key` alone instead of the program's writer lock,
  // so writers of different keys commit side by side (and the server flushes their commits
  // together) while writers of one key follow each other. With `programWide` it takes both (the
  // writer lock first): for a write that also reads or changes what all writers share, such as
  // enrolling a participant. SQLite has one writer anyway: there it is writeTransaction.
  Status keyedWriteTransaction(const std::string& key, const std::function<Status(Database&)>& body,
                               bool programWide = false, int maxAttempts = 20);

 private:
  friend class Transaction;
  Status migrate(int target);
  explicit Database(std::unique_ptr<detail::Connection> connection);
  std::unique_ptr<detail::Connection> connection_;
  bool readOnly_ = false;
  std::unique_ptr<std::recursive_mutex> writer_;  // held by the thread inside a write transaction
  int writeDepth_ = 0;  // > 0 while that thread runs a writeTransaction's body (nested ones join it)
};

// Runs `each` (Status(Statement&)) for every row of a prepared, bound statement; stops at the
// first error, its own or the statement's.
template <class F>
Status forEachRow(Statement& s, F&& each) {
  while (true) {
    auto row = s.step();
    if (!row) return tl::unexpected(row.error());
    if (!*row) return {};
    if (Status st = each(s); !st) return st;
  }
}

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

}  // namespace at::db
