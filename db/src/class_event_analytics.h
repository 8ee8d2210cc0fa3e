// The students a class server knows only from their class events (learners on their own machines,
// whose answers and lesson starts and ends came through the outbox: class_server.h), as instructor
// analytics reads a class: users, answers and lesson attempts, so that `analytics` on a server
// counts what `class progress` counts.
#pragma once

#include <optional>
#include <set>
#include <string>

#include "database.h"
#include "lessons/analytics.h"

namespace at::db {

// Adds to `in` every student member of a class on this database (of class `classCode` only, when
// given) who is not a user here (`localNames`): a student with a negative id and the class code
// as group; their answers to `in.course`'s questions and their attempts at its lessons, rebuilt
// from the events (a lesson_finished closes the latest attempt of that lesson started before it).
// Answers the server keeps as practice are left out; answers waiting for their keys (correct blank)
// are left out too and counted in `in.waitingAnswers`.
// On a class server, their exams graded there and handed in become attempts at the course's exams.
// What the events do not carry is left out: memory states (FSRS).
Status addClassEventStudents(Database& db, lessons::AnalyticsInput& in, const std::set<std::string>& localNames,
                             const std::set<std::string>& courseQuestions, const std::optional<std::string>& classCode);

}  // namespace at::db
