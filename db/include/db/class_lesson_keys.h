// A course's answer keys on a class server, which grades lesson and review answers with them
// (db/src/class_lesson_keys_sql.cpp): the laptop's `correct` and `score` are never believed there.
// An instructor or coordinator resolves the keys on their machine, which has the course's dataset
// (quiz::resolveQuestion), and publishes them; no login can read them back.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/error.h"
#include "db/connection.h"
#include "lessons/curriculum.h"
#include "quiz/grading.h"
#include "quiz/keys.h"

namespace at::db {

// The key of one resolved question as the server grades with it (a JSON object): its kind and
// target, the offered choices and key choice (identify, relation), the tolerance (locate), the
// structures the path meets in order and every structure's id and normalised spellings (order), the
// spellings without side words of the target and of the others, its side and whether it is asked
// (name; as setNameKey in class_exams.h). A locate key holds `locateViews` (a JSON array of the
// question's fixed views: [{view, width, height, runs: [[y, x_from, x_to], …]}]) when given: the
// server grades a pixel picked on one of them and keeps every other locate answer as practice
// (class_lesson_locate_sql.cpp).
std::string lessonKeyJson(const quiz::ResolvedQuestion& question, const quiz::GradingContext& context,
                          const std::string& locateViews = "");

// The keys of every question step of `course`, resolved through `keys`; a locate question's key
// holds its views from `locateViews` (by question id) when it is there. An error names the
// question that cannot be resolved.
Result<std::vector<std::string>> courseLessonKeys(const lessons::Course& course, quiz::KeyComputer& keys,
                                                  const quiz::GradingContext& context,
                                                  const std::map<std::string, std::string>& locateViews = {});

// Publishes (or replaces) `keys` (lessonKeyJson objects) for class `code` on `server`, as `by`
// (a person's login acts as itself; see class_accounts.h). Answers the class already sent to those
// questions are graded again. Returns the number of keys. Only the class's instructors and
// coordinators may; every question must be on the server with the same kind and target.
Result<int> publishLessonKeys(Database& server, const std::string& code, const std::vector<std::string>& keys,
                              const std::optional<std::string>& by);

}  // namespace at::db
