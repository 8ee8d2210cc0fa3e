// Storing courses: seeding the default course from data/courses/*.json and importing others.
// Idempotent: a course is keyed by its id, and its content is replaced only when the file's
// `version` is newer than the stored one, so re-seeding never duplicates anything. Learner data
// (attempts, responses, progress) is never touched by seeding.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "db/connection.h"
#include "lessons/curriculum.h"

namespace at::db {

enum class SeedOutcome {
  Added,      // the course was not stored
  Updated,    // a lower version was stored and has been replaced
  Unchanged,  // the same version is stored: nothing written
  KeptNewer,  // a higher version is stored: nothing written
};
const char* toString(SeedOutcome outcome);

// Stores `course` (lessons, prerequisites, steps, questions) in one transaction. Errors: a lesson
// or question id already used by another course (naming it).
Result<SeedOutcome> storeCourse(Database& db, const lessons::Course& course, const std::string& source);

struct SeedReport {
  std::string file;
  std::string courseId;
  SeedOutcome outcome = SeedOutcome::Unchanged;
};

// Loads every *.json in `dir` (sorted by name) with lessons::loadCourseJson and stores it.
// A file that does not parse is an error naming it; courses before it stay stored.
Result<std::vector<SeedReport>> seedCourses(Database& db, const std::filesystem::path& dir);

}  // namespace at::db
