#include "course_authoring.h"

#include <algorithm>
#include <cctype>
#include <fstream>
#include <map>
#include <set>

#include "core/atomic_file.h"
#include "lessons/course_check.h"
#include "lessons/course_json.h"

namespace at::app {


Status checkCourseFits(lessons::CurriculumRepository& curriculum, const lessons::Course& course, db::SeedOutcome& outcome) {
  auto all = curriculum.courses();
  if (!all) return tl::unexpected(all.error());
  std::map<std::string, std::string> owner;  // lesson/question/exam id -> course id
  outcome = db::SeedOutcome::Added;
  for (const lessons::Course& other : *all) {
    if (other.id == course.id) {
      if (other.datasetId != course.datasetId)
        return fail(ErrorKind::Conflict, "course '" + course.id + "' is already stored on dataset '" + other.datasetId +
                                             "'; this one is on '" + course.datasetId + "'");
      if (other.version > course.version)
        return fail(ErrorKind::Conflict, "course '" + course.id + "': version " + std::to_string(other.version) +
                                             " is stored, newer than this one's version " + std::to_string(course.version));
      if (other.version == course.version) {
        if (lessons::courseToJson(other) != lessons::courseToJson(course))
          return fail(ErrorKind::Conflict, "course '" + course.id + "' version " + std::to_string(course.version) +
                                               " is stored with other content; raise this one's version to replace it");
        outcome = db::SeedOutcome::Unchanged;
      } else {
        outcome = db::SeedOutcome::Updated;
      }
      continue;
    }
    for (const lessons::Lesson& l : other.lessons) {
      owner[l.id] = other.id;
      for (const lessons::Step& s : l.steps)
        if (s.kind == lessons::StepKind::Question) owner[s.question.id] = other.id;
    }
    for (const lessons::ExamSpec& e : other.exams) owner[e.id] = other.id;
  }
  const auto taken = [&](const std::string& what, const std::string& id) -> Status {
    if (auto it = owner.find(id); it != owner.end())
      return fail(ErrorKind::Conflict, "course '" + course.id + "': " + what + " id '" + id + "' is already used by course '" +
                                           it->second + "'");
    return {};
  };
  for (const lessons::Lesson& l : course.lessons) {
    if (auto ok = taken("lesson", l.id); !ok) return ok;
    for (const lessons::Step& s : l.steps)
      if (s.kind == lessons::StepKind::Question)
        if (auto ok = taken("question", s.question.id); !ok) return ok;
  }
  for (const lessons::ExamSpec& e : course.exams)
    if (auto ok = taken("exam", e.id); !ok) return ok;
  return {};
}

Status checkCourseAgainstDataset(LearningSession& session, const lessons::Course& course, const std::string& source) {
  auto structures = session.structures(course.datasetId);
  if (!structures) return tl::unexpected(withContext(source + ": dataset '" + course.datasetId + "'", structures.error()));
  std::set<std::string> ids;
  for (const Structure& s : *structures) ids.insert(s.id);
  return lessons::checkStructureReferences(course, ids, source);
}

Result<db::SeedOutcome> saveCourse(LearningSession& session, const lessons::Course& course, const std::string& source) {
  if (auto ok = checkCourseAgainstDataset(session, course, source); !ok) return tl::unexpected(ok.error());
  db::SeedOutcome outcome = db::SeedOutcome::Added;
  if (auto ok = checkCourseFits(session.curriculum(), course, outcome); !ok) return tl::unexpected(withContext(source, ok.error()));
  return db::storeCourse(session.database(), course, source);
}

Result<lessons::Course> starterCourse(LearningSession& session, const std::string& id, const std::string& datasetId,
                                      const std::string& title) {
  const bool plainId = !id.empty() && std::all_of(id.begin(), id.end(), [](unsigned char c) {
    return std::islower(c) || std::isdigit(c) || c == '_';
  });
  if (!plainId) return fail("course id '" + id + "': use lower-case letters, digits and '_'");
  if (auto stored = session.curriculum().course(id); stored)
    return fail(ErrorKind::Conflict, "course '" + id + "' already exists (version " + std::to_string(stored->version) + ")");
  auto structures = session.structures(datasetId);
  if (!structures) return tl::unexpected(structures.error());
  if (structures->empty())
    return fail("dataset '" + datasetId + "' has no structures: import it with a label map (--labels) first");

  lessons::Course course;
  course.id = id;
  course.datasetId = datasetId;
  course.title = title.empty() ? datasetId + " course" : title;
  course.summary = "A tour of " + datasetId + "'s structures.";
  lessons::Lesson tour;
  tour.id = id + ".tour";
  tour.courseId = id;
  tour.title = "Tour";
  tour.summary = "Each structure, then its name.";
  for (const Structure& s : *structures) {
    lessons::Step show;
    show.kind = lessons::StepKind::Show;
    show.show.structure = s.id;
    show.show.presetId = s.id + "_wdt";
    show.show.title = s.displayName.empty() ? s.id : s.displayName;
    show.show.text = s.description.empty() ? show.show.title + "." : s.description;
    tour.steps.push_back(show);
  }
  for (const Structure& s : *structures) {
    lessons::Step ask;
    ask.kind = lessons::StepKind::Question;
    ask.question.id = tour.id + ".name_" + s.id;
    ask.question.kind = quiz::QuestionKind::Name;
    ask.question.prompt = "Name the highlighted structure.";
    ask.question.target = s.id;
    tour.steps.push_back(ask);
  }
  course.lessons.push_back(std::move(tour));
  // Through the strict reader, so that the course is one a file could hold.
  return lessons::parseCourseJson(lessons::courseToJson(course), "course '" + id + "'");
}

Status writeCourseJson(const lessons::Course& course, const std::filesystem::path& file) {
  return writeFileAtomically(file.string(), lessons::courseToJson(course) + "\n");
}

}  // namespace at::app
