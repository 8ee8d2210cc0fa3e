// The class server's checks on study writes: a current coordinator, the drawn counterbalancing row
// (PostgreSQL only; study_checks_sql.cpp says what, schema.cpp runs it).
#pragma once

#include <string_view>

namespace at::db {

std::string_view studyChecksSql();

}  // namespace at::db
