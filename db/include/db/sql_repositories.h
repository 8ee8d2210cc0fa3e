// The storage interfaces of lessons/ (lessons/repositories.h) implemented in SQL over a Database,
// whichever backend it opened (SQLite file or PostgreSQL class server). Each repository borrows a
// Database that must outlive it; every write is one transaction committed before the call returns,
// retried when another process holds the write lock.
#pragma once

#include <functional>
#include <set>
#include <optional>
#include <string>
#include <vector>

#include "db/connection.h"
#include "lessons/repositories.h"

namespace at::db {

// Structures of datasets that are not in the database (the built-in phantom): nullopt for names
// it does not know. The app passes one built on volume/'s phantom; db/ does not build volumes.
using BuiltinStructures = std::function<std::optional<std::vector<Structure>>(const std::string& datasetId)>;

class SqlCurriculumRepository final : public lessons::CurriculumRepository {
 public:
  explicit SqlCurriculumRepository(Database& db, BuiltinStructures builtin = {});
  Result<std::vector<lessons::Course>> courses() override;
  Result<lessons::Course> course(const std::string& courseId) override;
  Result<lessons::Lesson> lesson(const std::string& lessonId) override;
  Result<quiz::Question> question(const std::string& questionId) override;
  Result<std::vector<Structure>> structures(const std::string& datasetId) override;
  std::vector<std::string> takeSkipped() override;

 private:
  // Records a damaged row left out (once per message).
  void skip(const std::string& what);

  Database& db_;
  BuiltinStructures builtin_;
  std::set<std::string> skippedEver_;
  std::vector<std::string> skippedNew_;
};

class SqlUserRepository final : public lessons::UserRepository {
 public:
  explicit SqlUserRepository(Database& db) : db_(db) {}
  Result<std::optional<lessons::User>> findUser(const std::string& name) override;
  Result<lessons::User> user(std::int64_t userId) override;
  Result<lessons::User> createUser(const std::string& name, lessons::Role role, const std::string& group) override;
  Result<std::vector<lessons::User>> users() override;

 private:
  Database& db_;
};

class SqlProgressRepository final : public lessons::ProgressRepository {
 public:
  explicit SqlProgressRepository(Database& db) : db_(db) {}
  Result<std::optional<lessons::Attempt>> openAttempt(std::int64_t userId, const std::string& lessonId) override;
  Result<lessons::Attempt> startAttempt(std::int64_t userId, const std::string& lessonId, lessons::LessonMode mode,
                                        lessons::UnixSeconds startedAt) override;
  Status finishAttempt(std::int64_t attemptId, lessons::UnixSeconds finishedAt, double score) override;
  Result<bool> hasFinished(std::int64_t userId, const std::string& lessonId) override;
  Result<std::vector<lessons::Response>> responses(std::int64_t attemptId) override;
  Result<std::int64_t> recordAnswer(const lessons::AnswerRecord& record) override;
  Result<std::int64_t> recordReviewAnswer(const lessons::ReviewRecord& record) override;
  Result<std::vector<lessons::ReviewResponse>> reviewResponses(std::int64_t userId) override;
  Result<std::vector<lessons::ReviewLogEntry>> reviewLog(std::int64_t userId) override;
  Result<std::optional<lessons::StructureProgress>> progress(std::int64_t userId,
                                                             const std::string& structureId) override;
  Result<std::vector<lessons::StructureProgress>> allProgress(std::int64_t userId) override;
  Result<std::optional<double>> ability(std::int64_t userId) override;
  Result<std::optional<double>> questionDifficulty(const std::string& questionId) override;

  Result<std::vector<lessons::Attempt>> attempts(std::int64_t userId) override;

 private:
  Database& db_;
};

}  // namespace at::db
