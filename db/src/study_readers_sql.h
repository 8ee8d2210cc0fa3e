// The class server's study readers: a study's owner reads it only while she coordinates a class
// (PostgreSQL only; study_readers_sql.cpp says what, schema.cpp runs it).
#pragma once

#include <string_view>

namespace at::db {

std::string_view studyReadersSql();

}  // namespace at::db
