// One learner's work over the database, set up in one place and shared by `play`, `progress`,
// `courses`, `lessons` and every desktop panel: the process's one database connection (seeded
// with the course folder's courses), the repositories over it, the user (found, or created on
// request), the answer keys of each course's dataset (the dataset is loaded only when a key needs
// it; distance fields by wdt/answer_keys.h's recipe) and lesson engines.
//
// Threads: the connection serialises its calls and one write transaction at a time (db/), so a
// lesson engine may start on a thread of its own while the UI thread records a study rating; the
// session's own state (users, keys) belongs to the thread that made the session, except that a
// started engine uses the keys it was given.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "db/connection.h"
#include "lessons/lesson_engine.h"
#include "lessons/repositories.h"
#include "quiz/keys.h"
#include "volume/structure.h"

namespace at::app {

// Used when no --user is given to the desktop. `anatomy-tutor play --user student --new-user` and
// `anatomy-tutor progress --user student` then see the same progress.
inline constexpr const char* kDefaultLessonUser = "student";

// The course folder: dataSubdirectory("courses") (data_paths.h: $AT_DATA_DIR, else the installed data).
std::string courseDirectory();

class LearningSession {
 public:
  // Opens `dbPath` (nullopt: the default database, its folder created when missing) and seeds the
  // courses of courseDirectory() (idempotent). With `readOnly` (commands that only read: courses,
  // lessons, progress), a database this process cannot write is opened read-only and not seeded.
  static Result<std::unique_ptr<LearningSession>> open(const std::optional<std::string>& dbPath,
                                                        bool readOnly = false);
  ~LearningSession();
  LearningSession(const LearningSession&) = delete;
  LearningSession& operator=(const LearningSession&) = delete;

  // The connection, for the stores that take one (datasets, presets, studies).
  db::Database& database() { return connection_; }
  lessons::CurriculumRepository& curriculum();
  lessons::ProgressRepository& progress();
  lessons::UserRepository& users();

  enum class NewUser { Refuse, Create };
  // The user called `name`. When there is none: created as a student in `group` (Create), or a
  // NotFound error saying how to create one (Refuse). `created` (optional) tells which happened.
  Result<lessons::User> user(const std::string& name, NewUser newUser, const std::string& group = "",
                             bool* created = nullptr);

  // The structures of a course's dataset (built-in, imported or known), by id.
  Result<std::vector<Structure>> structures(const std::string& datasetId);
  // The answer keys of questions on `datasetId`; the key computer lives as long as the session.
  Result<quiz::KeyComputer*> keysFor(const std::string& datasetId);
  // An engine for `lessonId` over this session's repositories and the keys of its course's
  // dataset; start() it (possibly on another thread) to begin or resume the user's attempt.
  Result<std::unique_ptr<lessons::LessonEngine>> engineFor(const std::string& lessonId);

 private:
  struct Repositories;
  explicit LearningSession(db::Connection connection);
  db::Connection connection_;
  std::unique_ptr<Repositories> repositories_;
  std::map<std::string, std::unique_ptr<quiz::KeyComputer>> keys_;  // by dataset id
};

// For typed answers: lower-cased ids and display names of `structures` → their ids.
std::map<std::string, std::string> structureIdsByName(const std::vector<Structure>& structures);

}  // namespace at::app
