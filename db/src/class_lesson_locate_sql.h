// Lesson locate answers graded on the class server from the pixel picked on the question's fixed
// view, or kept there as practice (class_lesson_locate_sql.cpp says what, schema.cpp runs it).
#pragma once

#include <string_view>

namespace at::db {

// The column both backends get (class_events.practice) and PostgreSQL's whole text.
std::string_view classLessonLocateSqliteSql();
std::string_view classLessonLocateSql();

}  // namespace at::db
