// Exam attempts (lessons/exam.h's ExamRepository) over a Database of either backend (SQLite or
// PostgreSQL). Borrows a Database that must outlive it; every write is one transaction committed
// before the call returns.
#pragma once

#include "db/connection.h"
#include "lessons/exam.h"

namespace at::db {

class SqlExamRepository final : public lessons::ExamRepository {
 public:
  explicit SqlExamRepository(Database& db) : db_(db) {}
  Result<std::optional<lessons::ExamAttempt>> openExamAttempt(std::int64_t userId, const std::string& examId) override;
  Result<lessons::ExamAttempt> startExamAttempt(const lessons::ExamAttempt& attempt,
                                                std::vector<lessons::ExamItem>& items) override;
  Result<std::vector<lessons::ExamItem>> examItems(std::int64_t attemptId) override;
  Status recordExamAnswer(const lessons::ExamAnswerRecord& record) override;
  Status finishExamAttempt(std::int64_t attemptId, lessons::UnixSeconds finishedAt, double score,
                           std::optional<bool> passed) override;
  Result<std::vector<lessons::ExamAttempt>> examAttempts(std::int64_t userId) override;
  // Every attempt at the exams of a course, by every user (instructor analytics), oldest first.
  Result<std::vector<lessons::ExamAttempt>> courseExamAttempts(const std::string& courseId);

 private:
  Database& db_;
};

}  // namespace at::db
