// Graded exams on a class server from the terminal (cmd_class_exam.cpp).
#pragma once

#include <optional>
#include <string>

#include "cli_args.h"
#include "learning_session.h"
#include "lessons/xapi.h"
#include "terminal_answers.h"

namespace at::app {

// `class open-exam CODE EXAM --db SERVER [--local-db PATH] [--views DIR]` and `class close-exam`.
int runClassOpenExam(const cli::Args& args);
int runClassCloseExam(const cli::Args& args);
// `class keys CODE --db SERVER [--course ID] [--local-db PATH]` (cmd_class_keys.cpp).
int runClassKeys(const cli::Args& args);
// Publishes the answer keys of `courses` (their locate questions' pixels included) to class `code`
// on `server` as `by`, printing a line per course. A course whose dataset is not on this machine
// is skipped with a line saying what to run, or fails when `stopAtFirstMissing`. Without
// `locatePixels` the locate keys hold no views (their answers are practice until `class keys`
// publishes them; the line says so). Returns how many keys were published.
Result<int> publishClassKeys(db::Database& server, const std::string& code, LearningSession& session,
                             const std::vector<lessons::Course>& courses, const std::optional<std::string>& by,
                             bool stopAtFirstMissing, bool locatePixels);

// When `userName` joined a class whose server has `examId` open, sits it there (items from the
// server, answers graded there) and returns the exit status; nullopt when the exam is this
// machine's to give (no class, the exam not open there, or the server not reachable: practice).
std::optional<int> runServerExam(LearningSession& session, const std::string& userName, const std::string& examId,
                                 AnswerSource& source, const std::optional<std::string>& viewsDir, bool noViews);

// The graded exams of class `code` on `server` as xAPI learner records (each member's sittings
// with their graded answers; the items carry their choices but not their keys, which stay on the
// server), for an instructor's or coordinator's login.
Result<std::vector<lessons::LearnerRecords>> classExamLearners(db::Database& server, const std::string& code);

}  // namespace at::app
