// The schema as forward-only migrations. Migration N takes a database from version N-1 to N
// inside one transaction; versions are never edited once released — a change is a new migration.
//
// Each migration is written once, in SQLite's dialect. On PostgreSQL the same text runs after a
// fixed set of rewrites (postgresDdl): INTEGER PRIMARY KEY becomes an identity column, INTEGER
// BIGINT, REAL DOUBLE PRECISION, and SQLite's timestamp default the same text from PostgreSQL's
// clock. A migration whose text uses other SQLite-only functions lists the exact replacements its
// PostgreSQL text needs (`postgresEdits`).
#pragma once

#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "database.h"

namespace at::db {

struct Migration {
  int version;              // schema version after this migration
  std::string_view summary; // what it adds, for messages and tests
  std::string_view sql;     // statements run in one transaction (SQLite's dialect)
  // Exact text replacements (each must occur) for PostgreSQL, applied after postgresDdl.
  std::vector<std::pair<std::string_view, std::string_view>> postgresEdits = {};
  // PostgreSQL's text, run there as it is; on SQLite the step only moves the version (server-only
  // objects: roles, grants, row-level security, functions).
  bool postgresOnly = false;
  // PostgreSQL's own text for a step whose dialects differ beyond edits (run there as it is, in
  // place of `sql`); empty: `sql` through postgresDdl and postgresEdits.
  std::string_view postgresSql = {};
};

// All migrations in order; migrations()[i].version == i + 1.
const std::vector<Migration>& migrations();

// The newest schema version this program knows.
int latestSchemaVersion();

// The type and default rewrites that make SQLite DDL PostgreSQL DDL (see above).
std::string postgresDdl(std::string_view sqliteSql);

// The text of `migration` for `backend`.
std::string migrationSql(const Migration& migration, Backend backend);

}  // namespace at::db
