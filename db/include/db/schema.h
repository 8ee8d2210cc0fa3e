// The schema as forward-only migrations. Migration N takes a database from user_version N-1 to N
// inside one transaction; versions are never edited once released — a change is a new migration.
#pragma once

#include <string_view>
#include <vector>

namespace at::db {

struct Migration {
  int version;              // user_version after this migration
  std::string_view summary; // what it adds, for messages and tests
  std::string_view sql;     // statements run in one transaction
};

// All migrations in order; migrations()[i].version == i + 1.
const std::vector<Migration>& migrations();

// The newest schema version this program knows.
int latestSchemaVersion();

}  // namespace at::db
