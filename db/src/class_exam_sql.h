// The PostgreSQL-only migration for graded exams on a class server (class_exam_sql.cpp says what).
#pragma once

#include <string_view>

namespace at::db {

// PostgreSQL text, run as it is in the schema the connection's search_path selects.
std::string_view classExamSql();

}  // namespace at::db
