// Authoring courses in the database: a starter course on a dataset, the checks a course passes
// before it is stored (its structure references and its ids against the stored courses), and
// storing it. `anatomy-tutor course new|validate|import F.json`, course packages and the
// desktop's course editor share these.
#pragma once

#include <filesystem>
#include <string>

#include "core/error.h"
#include "db/course_store.h"
#include "learning_session.h"
#include "lessons/curriculum.h"

namespace at::app {

// Whether `course` may be stored: its id free, or held by an older version of itself on the same
// dataset, or by the very same content (then `outcome` is Unchanged); none of its lesson, question
// or exam ids used by another course. Conflict errors name the id and the course holding it.
Status checkCourseFits(lessons::CurriculumRepository& curriculum, const lessons::Course& course, db::SeedOutcome& outcome);

// The structures of `course`'s dataset, and every structure reference checked against them
// ("<source>: lessons[0].steps[2].question.target: no structure 'x' in dataset 'd'").
Status checkCourseAgainstDataset(LearningSession& session, const lessons::Course& course, const std::string& source);

// Checks (both of the above) and stores `course`; `source` is recorded with it and prefixes errors.
Result<db::SeedOutcome> saveCourse(LearningSession& session, const lessons::Course& course, const std::string& source);

// A course to start from on `datasetId` (built in or imported, with structures): one lesson,
// "<id>.tour", showing each structure (its "<structure>_wdt" preset, described by its
// description) and asking to name it. `id` must be lower-case letters, digits and '_', and not a
// stored course's; the title defaults to "<dataset> course".
Result<lessons::Course> starterCourse(LearningSession& session, const std::string& id, const std::string& datasetId,
                                      const std::string& title);

// Writes `course` as a course JSON file (through a temporary file renamed into place).
Status writeCourseJson(const lessons::Course& course, const std::filesystem::path& file);

}  // namespace at::app
