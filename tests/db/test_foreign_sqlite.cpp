// Another program's SQLite file given as --db is refused before anything is written to it, and stays
// byte-identical; our own files from before the application id still migrate, and get the mark.
#include <doctest/doctest.h>

#include <sqlite3.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "database.h"  // db/'s private SQL wrapper (at_db_sql_for_tests)
#include "db/checksum.h"
#include "schema.h"
#include "test_support.h"

using namespace at;
using namespace at::db;
namespace fs = std::filesystem;

namespace {

// Runs `sql` on `path` with SQLite itself (not through Database, which would migrate the file).
void rawSql(const fs::path& path, const std::string& sql) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open(path.c_str(), &db) == SQLITE_OK);
  char* error = nullptr;
  const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error);
  const std::string message = error ? error : "";
  sqlite3_free(error);
  sqlite3_close(db);
  REQUIRE_MESSAGE(rc == SQLITE_OK, message);
}

long applicationIdOf(const fs::path& path) {
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK);
  sqlite3_stmt* stmt = nullptr;
  long id = -1;
  if (sqlite3_prepare_v2(db, "PRAGMA application_id", -1, &stmt, nullptr) == SQLITE_OK && sqlite3_step(stmt) == SQLITE_ROW)
    id = long(sqlite3_column_int64(stmt, 0));
  sqlite3_finalize(stmt);
  sqlite3_close(db);
  return id;
}

std::string fileChecksum(const fs::path& path) { return sha256Hex(test::readFile(path)); }

}  // namespace

TEST_CASE("ForeignSqlite_AnotherProgramsFile_RefusedWithOneLineAndByteIdentical") {
  test::TempDir dir;
  struct Case {
    const char* name;
    const char* sql;
    const char* mention;
  };
  const Case cases[] = {
      {"browser.db", "CREATE TABLE moz_places (id INTEGER PRIMARY KEY, url TEXT); INSERT INTO moz_places VALUES (1, 'x');",
       "moz_places"},
      {"geo.gpkg", "PRAGMA application_id = 1196444487; CREATE TABLE gpkg_contents (table_name TEXT);", "application id"},
      {"marked-empty.db", "PRAGMA application_id = 42; PRAGMA user_version = 1;", "application id"},
      {"versioned.db", "PRAGMA user_version = 3; CREATE TABLE notes (body TEXT);", "notes"},
      // One of our table names is not enough: the fingerprint wants ours, together.
      {"lookalike.db", "CREATE TABLE courses (id TEXT); CREATE TABLE recipes (id TEXT);", "recipes"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.name);
    const fs::path path = dir / c.name;
    rawSql(path, c.sql);
    const std::string before = fileChecksum(path);
    const auto listing = [&] {
      std::string names;
      for (const auto& e : fs::directory_iterator(dir.path())) names += e.path().filename().string() + " ";
      return names;
    };
    const std::string filesBefore = listing();
    auto db = Database::open(path.string());
    REQUIRE_FALSE(db);
    const std::string& message = db.error().message;
    CAPTURE(message);
    CHECK(message.rfind(path.string() + ": not an Anatomy Tutor database", 0) == 0);
    CHECK(message.find(c.mention) != std::string::npos);
    CHECK(message.find("left untouched") != std::string::npos);
    CHECK(message.find('\n') == std::string::npos);
    CHECK(fileChecksum(path) == before);
    CHECK(listing() == filesBefore);  // no -wal or -shm beside it either
  }
}

TEST_CASE("ForeignSqlite_OurFileFromBeforeTheMark_MigratesAndIsMarked") {
  test::TempDir dir;
  const fs::path path = dir / "old.db";
  {
    OpenOptions options;
    options.targetVersion = 3;
    auto db = Database::open(path.string(), options);
    REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
  }
  rawSql(path, "PRAGMA application_id = 0");  // as every file written before the mark
  CHECK(applicationIdOf(path) == 0);
  {
    auto db = Database::open(path.string());
    REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
    auto version = db->schemaVersion();
    REQUIRE(version);
    CHECK(*version == latestSchemaVersion());
  }
  CHECK(applicationIdOf(path) == 0x41547574);
}

TEST_CASE("ForeignSqlite_NewOrEmptyFile_BecomesOursAndIsMarked") {
  test::TempDir dir;
  for (const bool emptyFileFirst : {false, true}) {
    const fs::path path = dir / (emptyFileFirst ? "empty.db" : "new.db");
    if (emptyFileFirst) std::ofstream(path).flush();
    {
      auto db = Database::open(path.string());
      REQUIRE_MESSAGE(db, (db ? "" : db.error().message));
    }
    CHECK(applicationIdOf(path) == 0x41547574);
    auto again = Database::open(path.string());
    CHECK(again);
  }
}
