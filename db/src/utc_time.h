// Times as the database stores them in its TEXT columns: ISO 8601 UTC with milliseconds
// ("2026-11-22T05:01:02.345Z"), the same text on SQLite and PostgreSQL. Computed here and bound as
// a parameter rather than by an SQL function, so no statement depends on a dialect's clock.
#pragma once

#include <string>

namespace at::db {

std::string utcTimestampNow();

}  // namespace at::db
