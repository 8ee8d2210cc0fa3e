#include "db/course_store.h"

#include <algorithm>

#include <nlohmann/json.hpp>

#include "database.h"
#include "lessons/course_json.h"

namespace at::db {

const char* toString(SeedOutcome outcome) {
  switch (outcome) {
    case SeedOutcome::Added: return "added";
    case SeedOutcome::Updated: return "updated";
    case SeedOutcome::Unchanged: return "unchanged";
    case SeedOutcome::KeptNewer: return "kept newer";
  }
  return "?";
}

namespace {

// Inserts one row; a primary-key clash means the id belongs to another course.
Status insertOwned(Statement& s, const std::string& what, const std::string& id, const std::string& courseId) {
  auto status = s.run();
  if (!status && status.error().kind == ErrorKind::Conflict)
    return fail(ErrorKind::Conflict, what + " id '" + id + "' of course '" + courseId + "' is already used by another course");
  return status;
}

Status writeCourse(Database& d, const lessons::Course& course, const std::string& source) {
  nlohmann::json synonyms = nlohmann::json::object();
  for (const auto& [structure, names] : course.synonyms) synonyms[structure] = names;

  auto upsert = d.prepare(
      "INSERT INTO courses (id, title, summary, dataset, version, synonyms, source) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)"
      " ON CONFLICT(id) DO UPDATE SET title = excluded.title, summary = excluded.summary,"
      " dataset = excluded.dataset, version = excluded.version, synonyms = excluded.synonyms, source = excluded.source");
  if (!upsert) return tl::unexpected(upsert.error());
  upsert->bind(1, course.id)
      .bind(2, course.title)
      .bind(3, course.summary)
      .bind(4, course.datasetId)
      .bind(5, course.version)
      .bind(6, synonyms.dump())
      .bind(7, source);
  if (auto s = upsert->run(); !s) return s;

  // Old content goes (steps, prerequisites and questions cascade with their lessons) …
  auto drop = d.prepare("DELETE FROM lessons WHERE course_id = ?1");
  if (!drop) return tl::unexpected(drop.error());
  drop->bind(1, course.id);
  if (auto s = drop->run(); !s) return s;

  // … and the new content comes in under the same stable ids.
  auto lesson = d.prepare("INSERT INTO lessons (id, course_id, position, title, summary) VALUES (?1, ?2, ?3, ?4, ?5)");
  auto prereq = d.prepare("INSERT INTO lesson_prerequisites (lesson_id, requires_id, position) VALUES (?1, ?2, ?3)");
  auto question = d.prepare(
      "INSERT INTO questions (id, lesson_id, kind, target, difficulty, json) VALUES (?1, ?2, ?3, ?4, ?5, ?6)");
  // Steps keep a camera and clip from schema 11 (tests build older versions with this code).
  auto version = d.schemaVersion();
  if (!version) return tl::unexpected(version.error());
  const bool placements = *version >= 12;
  auto step = d.prepare(placements ? "INSERT INTO steps (lesson_id, position, kind, structure, preset_id, view, title, text,"
                                     " question_id, study_items, placement) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11)"
                                   : "INSERT INTO steps (lesson_id, position, kind, structure, preset_id, view, title, text,"
                                     " question_id, study_items) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)");
  for (auto* s : {&lesson, &prereq, &question, &step})
    if (!*s) return tl::unexpected(s->error());

  for (std::size_t li = 0; li < course.lessons.size(); ++li) {
    const lessons::Lesson& l = course.lessons[li];
    lesson->reset();
    lesson->bind(1, l.id).bind(2, course.id).bind(3, int(li)).bind(4, l.title).bind(5, l.summary);
    if (auto s = insertOwned(*lesson, "lesson", l.id, course.id); !s) return s;
    for (std::size_t pi = 0; pi < l.prerequisites.size(); ++pi) {
      prereq->reset();
      prereq->bind(1, l.id).bind(2, l.prerequisites[pi]).bind(3, int(pi));
      if (auto s = prereq->run(); !s) return tl::unexpected(withContext("lesson '" + l.id + "' prerequisites", s.error()));
    }
    for (std::size_t si = 0; si < l.steps.size(); ++si) {
      const lessons::Step& st = l.steps[si];
      std::optional<std::string> questionId;
      std::string structure;
      std::string scenePreset, sceneView, placement;
      if (st.kind == lessons::StepKind::Question) {
        const quiz::Question& q = st.question;
        question->reset();
        question->bind(1, q.id)
            .bind(2, l.id)
            .bind(3, quiz::toString(q.kind))
            .bind(4, q.target)
            .bind(5, q.difficulty)
            .bind(6, lessons::questionToJson(q));
        if (auto s = insertOwned(*question, "question", q.id, course.id); !s) return s;
        questionId = q.id;
        structure = q.target;
        if (st.scene) {  // stored in the show columns; an empty view means "no scene"
          structure = st.scene->structure;
          scenePreset = st.scene->presetId;
          sceneView = lessons::toString(st.scene->view);
          placement = lessons::placementToJson(st.scene->camera, st.scene->clip);
        }
      } else if (st.kind == lessons::StepKind::Show) {
        structure = st.show.structure;
        placement = lessons::placementToJson(st.show.camera, st.show.clip);
      } else {
        structure = st.study.structure;
      }
      const bool show = st.kind == lessons::StepKind::Show;
      step->reset();
      step->bind(1, l.id)
          .bind(2, int(si))
          .bind(3, lessons::toString(st.kind))
          .bind(4, structure)
          .bind(5, show ? st.show.presetId : scenePreset)
          .bind(6, show ? std::string(lessons::toString(st.show.view)) : sceneView)
          .bind(7, show ? st.show.title : std::string())
          .bind(8, show ? st.show.text : std::string())
          .bind(9, questionId)
          .bind(10, nlohmann::json(st.study.items).dump());
      if (placements) step->bind(11, placement.empty() ? std::optional<std::string>() : std::optional<std::string>(placement));
      else if (!placement.empty())
        return fail("lesson '" + l.id + "' step " + std::to_string(si) + ": a camera or clip needs schema version 12; this database is at " +
                    std::to_string(*version));
      if (auto s = step->run(); !s)
        return tl::unexpected(withContext("lesson '" + l.id + "' step " + std::to_string(si), s.error()));
    }
  }

  // Exams came with schema 7 (a database is always migrated before courses are stored; tests build
  // older versions with this code, which then has no exams to keep).
  if (*version < 7) {
    if (!course.exams.empty()) return fail("exams need schema version 7; this database is at " + std::to_string(*version));
    return {};
  }
  auto dropExams = d.prepare("DELETE FROM exams WHERE course_id = ?1");
  if (!dropExams) return tl::unexpected(dropExams.error());
  dropExams->bind(1, course.id);
  if (auto s = dropExams->run(); !s) return s;
  auto exam = d.prepare("INSERT INTO exams (id, course_id, position, json) VALUES (?1, ?2, ?3, ?4)");
  if (!exam) return tl::unexpected(exam.error());
  for (std::size_t ei = 0; ei < course.exams.size(); ++ei) {
    exam->reset();
    exam->bind(1, course.exams[ei].id).bind(2, course.id).bind(3, int(ei)).bind(4, lessons::examToJson(course.exams[ei]));
    if (auto s = insertOwned(*exam, "exam", course.exams[ei].id, course.id); !s) return s;
  }
  return {};
}

}  // namespace

Result<SeedOutcome> storeCourse(Database& db, const lessons::Course& course, const std::string& source) {
  SeedOutcome outcome = SeedOutcome::Unchanged;
  auto status = db.writeTransaction([&](Database& d) -> Status {
    auto stored = d.prepare("SELECT version FROM courses WHERE id = ?1");
    if (!stored) return tl::unexpected(stored.error());
    stored->bind(1, course.id);
    auto row = stored->step();
    if (!row) return tl::unexpected(row.error());
    if (*row) {
      const int version = stored->integer(0);
      if (version == course.version) {
        outcome = SeedOutcome::Unchanged;
        return {};
      }
      if (version > course.version) {
        outcome = SeedOutcome::KeptNewer;
        return {};
      }
      outcome = SeedOutcome::Updated;
    } else {
      outcome = SeedOutcome::Added;
    }
    stored->reset();
    return writeCourse(d, course, source);
  });
  if (!status) return tl::unexpected(withContext("course '" + course.id + "'", status.error()));
  return outcome;
}

Result<std::vector<SeedReport>> seedCourses(Database& db, const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return fail(dir.string() + ": course folder not found");
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.is_regular_file() && entry.path().extension() == ".json") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  std::vector<SeedReport> reports;
  for (const auto& file : files) {
    auto course = lessons::loadCourseJson(file);
    if (!course) return tl::unexpected(course.error());
    auto outcome = storeCourse(db, *course, fs::absolute(file).string());
    if (!outcome) return tl::unexpected(withContext(file.string(), outcome.error()));
    reports.push_back({file.string(), course->id, *outcome});
  }
  return reports;
}

}  // namespace at::db
