// Checks a course against the structures of its dataset: every structure id a step, question,
// scene, synonym list or exam names must be one the dataset has. The course reader
// (course_json.h) checks the form; this checks the references, for `course validate`, course
// packages and the course editor's live validation.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "core/error.h"
#include "lessons/curriculum.h"

namespace at::lessons {

// One problem per reference to a structure the dataset lacks, as "<path>: no structure '<id>' in
// dataset '<dataset>'", the path in course-JSON form ("lessons[1].steps[3].question.target"), in
// course order.
std::vector<std::string> unknownStructureReferences(const Course& course, const std::set<std::string>& structureIds);

// The first of those as an Invalid error prefixed with `source` ("notes.json: lessons[0]…"), and
// how many more there are.
Status checkStructureReferences(const Course& course, const std::set<std::string>& structureIds, const std::string& source);

}  // namespace at::lessons
