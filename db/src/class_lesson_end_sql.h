// A lesson's end scored again on the class server whenever one of its answers is graded again
// (class_lesson_end_sql.cpp says how; schema.cpp runs it).
#pragma once

#include <string_view>

namespace at::db {

// PostgreSQL only (a SQLite file is one person's laptop, which holds no keys).
std::string_view classLessonEndSql();

}  // namespace at::db
