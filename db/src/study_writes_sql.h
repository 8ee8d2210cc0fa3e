// The PostgreSQL-only migration through which a study's coordinator registers it and records its
// participants on a class server (study_writes_sql.cpp says what).
#pragma once

#include <string_view>

namespace at::db {

// PostgreSQL text, run as it is in the schema the connection's search_path selects.
std::string_view studyWritesSql();

}  // namespace at::db
