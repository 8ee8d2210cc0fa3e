// The PostgreSQL-only migration that lets coordinators read the studies they own and withdraw or
// exclude their participants (study_security_sql.cpp says what).
#pragma once

#include <string_view>

namespace at::db {

// PostgreSQL text, run as it is in the schema the connection's search_path selects.
std::string_view studySecuritySql();

}  // namespace at::db
