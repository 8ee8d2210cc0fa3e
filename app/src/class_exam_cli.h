// Graded exams on a class server from the terminal (cmd_class_exam.cpp).
#pragma once

#include <optional>
#include <string>

#include "cli_args.h"
#include "learning_session.h"
#include "terminal_answers.h"

namespace at::app {

// `class open-exam CODE EXAM --db SERVER [--local-db PATH] [--views DIR]` and `class close-exam`.
int runClassOpenExam(const cli::Args& args);
int runClassCloseExam(const cli::Args& args);

// When `userName` joined a class whose server has `examId` open, sits it there (items from the
// server, answers graded there) and returns the exit status; nullopt when the exam is this
// machine's to give (no class, the exam not open there, or the server not reachable: practice).
std::optional<int> runServerExam(LearningSession& session, const std::string& userName, const std::string& examId,
                                 AnswerSource& source, const std::optional<std::string>& viewsDir, bool noViews);

}  // namespace at::app
