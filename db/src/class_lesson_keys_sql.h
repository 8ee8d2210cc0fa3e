// The class server's grading of lesson answers from published keys (PostgreSQL only; schema.cpp).
#pragma once

#include <string_view>

namespace at::db {

std::string_view classLessonKeysSql();

}  // namespace at::db
