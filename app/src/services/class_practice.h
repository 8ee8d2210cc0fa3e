// Locate answers a class server keeps as practice, and what the learner is told about them — the
// same words in terminal `play` and in the desktop's lesson player.
//
// A class server grades a lesson's (or review's) locate answer only from the pixel picked on the
// fixed picture `play` shows, with that picture's view id (db/src/class_lesson_locate_sql.cpp);
// any other locate pick — a click in the desktop's free 3-D view, a point in mm — is stored there
// as practice: left out of class progress and analytics.
#pragma once

#include <string>

#include "db/connection.h"
#include "quiz/question.h"

namespace at::app {

// Whether the answers `userName` records in `local` go to a class server: `local` is a machine's
// own file (SQLite) and the user joined a class on it (db::rememberMembership). False when the
// membership cannot be read (nothing then says the answers go anywhere).
bool answersGoToClassServer(db::Database& local, const std::string& userName);

// Whether a class server grades `pick`: a pixel with the id of the picture it was picked on.
bool classServerGrades(const quiz::Pick& pick);

// After a locate answer a class server keeps as practice (lower case, no full stop: the
// terminal prints it in brackets under the feedback, the desktop beneath it).
std::string practicePickNote();
// Before a locate question is answered in a free 3-D view (the desktop), for a user whose answers
// go to a class server: that a click there is kept as practice, and what counts instead.
std::string practiceClickAheadNote();

}  // namespace at::app
