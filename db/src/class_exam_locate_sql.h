// The PostgreSQL-only migration that grades locate items from the click itself and checks an
// exam's prerequisites on the server (class_exam_locate_sql.cpp says what).
#pragma once

#include <string_view>

namespace at::db {

// PostgreSQL text, run as it is in the schema the connection's search_path selects.
std::string_view classExamLocateSql();

}  // namespace at::db
