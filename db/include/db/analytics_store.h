// What instructor analytics read (lessons/analytics.h): one course's class — its students, their
// answers (the review log: lesson, review and exam answers alike), lesson attempts, FSRS memory
// states and exam attempts — loaded from the database.
#pragma once

#include <optional>
#include <string>

#include "db/connection.h"
#include "db/sql_repositories.h"
#include "lessons/analytics.h"

namespace at::db {

// The class is every user with the student role (of `group` when given), and every student member
// of a class on this database who is not a user here — learners whose answers and lessons reached
// a class server through the outbox (class_server.h), read from their class events, with the class
// code as their group (so `group` may name a class). Errors: unknown course.
// `curriculum` gives the course and its dataset's structures (the app's knows the built-in ones).
Result<lessons::AnalyticsInput> loadAnalyticsInput(Database& db, lessons::CurriculumRepository& curriculum,
                                                   const std::string& courseId, const std::optional<std::string>& group);

}  // namespace at::db
