#include "analytics/analytics_controller.h"

#include <algorithm>
#include <ctime>
#include <set>

#include "db/analytics_store.h"
#include "quiz/name_matching.h"

namespace at::app {

using json = nlohmann::json;

AnalyticsController::AnalyticsController(LearningSession& session, EventSink events, Now now)
    : session_(session), events_(std::move(events)), now_(std::move(now)) {
  if (!now_) now_ = [] { return lessons::UnixSeconds(std::time(nullptr)); };
}

std::optional<AnalyticsController::Tab> AnalyticsController::parseTab(const std::string& name) {
  if (name == "structures") return Tab::Structures;
  if (name == "missed") return Tab::MostMissed;
  if (name == "students") return Tab::Students;
  if (name == "lessons") return Tab::Lessons;
  return std::nullopt;
}

Result<std::vector<AnalyticsController::CourseChoice>> AnalyticsController::courses() {
  auto courses = session_.curriculum().courses();
  if (!courses) return tl::unexpected(courses.error());
  std::vector<CourseChoice> out;
  for (const lessons::Course& c : *courses) out.push_back({c.id, c.title});
  return out;
}

Status AnalyticsController::load(const std::string& courseId, const std::optional<std::string>& group) {
  // The whole class first (its groups are the choices), then the group's students.
  auto input = db::loadAnalyticsInput(session_.database(), session_.curriculum(), courseId, std::nullopt);
  if (!input) return tl::unexpected(withContext("analytics", input.error()));
  std::set<std::string> groups;
  for (const lessons::User& u : input->students)
    if (!u.group.empty()) groups.insert(u.group);
  if (group && !groups.count(*group)) {
    std::string known;
    for (const std::string& g : groups) known += (known.empty() ? "" : ", ") + g;
    return fail(ErrorKind::NotFound, "analytics: no student of course '" + courseId + "' is in group '" + *group + "'" +
                                         (known.empty() ? " (its students have no groups)" : " (groups: " + known + ")"));
  }
  if (group) std::erase_if(input->students, [&](const lessons::User& u) { return u.group != *group; });
  computedAt_ = now_();
  analytics_ = lessons::computeAnalytics(*input, computedAt_);
  course_ = input->course;
  structures_ = input->structures;
  group_ = group;
  groups_.assign(groups.begin(), groups.end());
  ++revision_;

  const lessons::ClassAnalytics& a = *analytics_;
  json structures = json::array(), missed = json::array(), students = json::array();
  for (const lessons::StructureStats& s : a.structures)
    structures.push_back({{"id", s.structureId}, {"answers", s.answers}, {"error_rate", 1 - s.correctShare}});
  for (const lessons::QuestionStats& q : mostMissed(10))
    missed.push_back({{"question", q.questionId}, {"missed", q.answers - q.correct}, {"answers", q.answers}});
  for (const lessons::StudentRecall& s : a.students)
    students.push_back({{"name", s.name},
                        {"lessons_finished", s.lessonsFinished},
                        {"taught", s.taught},
                        {"due", s.due},
                        {"mean_recall", s.meanRecall ? json(*s.meanRecall) : json(nullptr)},
                        {"exam_score", s.examScore ? json(*s.examScore) : json(nullptr)}});
  events_({{"event", "analytics"},
           {"course", courseId},
           {"group", group ? json(*group) : json(nullptr)},
           {"class_size", a.classSize},
           {"answers", a.answers},
           {"lessons", course_.lessons.size()},
           {"structures", structures},
           {"most_missed", missed},
           {"students", students}});
  return {};
}

Status AnalyticsController::refresh() {
  if (!loaded()) return fail("analytics: choose a course first");
  return load(course_.id, group_);
}

std::vector<lessons::QuestionStats> AnalyticsController::mostMissed(std::size_t limit) const {
  return loaded() ? lessons::mostMissed(*analytics_, limit) : std::vector<lessons::QuestionStats>{};
}

std::string AnalyticsController::displayName(const std::string& structureId) const {
  for (const Structure& s : structures_)
    if (s.id == structureId && !s.displayName.empty()) return s.displayName;
  return structureId;
}

std::string AnalyticsController::questionText(const lessons::QuestionStats& q) const {
  for (const lessons::Lesson& lesson : course_.lessons)
    for (const lessons::Step& step : lesson.steps)
      if (step.kind == lessons::StepKind::Question && step.question.id == q.questionId) return step.question.prompt;
  return "exam: " + q.kind + " the " + quiz::nameInSentence(displayName(q.structureId));
}

std::string AnalyticsController::titleOf(const std::string& lessonOrExamId) const {
  for (const lessons::Lesson& lesson : course_.lessons)
    if (lesson.id == lessonOrExamId) return lesson.title;
  for (const lessons::ExamSpec& exam : course_.exams)
    if (exam.id == lessonOrExamId) return exam.title;
  return lessonOrExamId;
}

}  // namespace at::app
