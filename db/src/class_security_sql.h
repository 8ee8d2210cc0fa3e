// The PostgreSQL-only migration that secures a class server (class_security_sql.cpp says what).
#pragma once

#include <string_view>

namespace at::db {

// PostgreSQL text, run as it is in the schema the connection's search_path selects.
std::string_view classSecuritySql();

}  // namespace at::db
