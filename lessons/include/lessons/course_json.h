// Course JSON (schema: data/courses/README.md). Strict: unknown fields, wrong types, missing
// required fields, bad enum values and duplicate ids are errors naming the field by its path
// ("temporal_bone.json: lessons[2].steps[4].question.kind: unknown kind 'pick'").
// Structure ids are checked against a dataset elsewhere (resolveQuestion, tests).
#pragma once

#include <filesystem>
#include <string>

#include "lessons/curriculum.h"
#include "quiz/question.h"
#include "core/error.h"

namespace at::lessons {

Result<Course> loadCourseJson(const std::filesystem::path& path);
// `sourceName` prefixes error messages.
Result<Course> parseCourseJson(const std::string& text, const std::string& sourceName);
std::string courseToJson(const Course& course);

// One question in the same schema as a course's question steps (for db/ to store questions as
// text). `sourceName` prefixes errors.
std::string questionToJson(const quiz::Question& question);
Result<quiz::Question> parseQuestionJson(const std::string& text, const std::string& sourceName);

// One exam in the course schema's "exams" form (db/ stores exams as text).
std::string examToJson(const ExamSpec& exam);
Result<ExamSpec> parseExamJson(const std::string& text, const std::string& sourceName);

// A step's free camera and clipping plane in the schema's form ({"camera": {…}, "clip": […]}; ""
// when it has neither), for db/ to store them as text; parsing fills what the text holds.
std::string placementToJson(const std::optional<StepCamera>& camera, const std::optional<StepClip>& clip);
Status parsePlacementJson(const std::string& text, const std::string& sourceName, std::optional<StepCamera>& camera,
                          std::optional<StepClip>& clip);

}  // namespace at::lessons
