#include "db/class_lesson_keys.h"

#include <nlohmann/json.hpp>

#include "database.h"
#include "db/class_exams.h"
#include "quiz/name_matching.h"
#include "server_refusal.h"

namespace at::db {

using nlohmann::json;

std::string lessonKeyJson(const quiz::ResolvedQuestion& question, const quiz::GradingContext& context,
                          const std::string& locateViews) {
  const quiz::Question& q = question.question;
  json key = {{"question_id", q.id}, {"kind", quiz::toString(q.kind)}, {"target", q.target}};
  switch (q.kind) {
    case quiz::QuestionKind::Locate:
      key["tolerance_mm"] = q.toleranceMm;
      if (!locateViews.empty()) key["views"] = json::parse(locateViews);
      break;
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation:
      key["choices"] = question.choices;
      key["key_choice"] = question.keyChoice;
      break;
    case quiz::QuestionKind::Name: {
      ClassExamKey names;
      setNameKey(names, question, context);
      key["name_bodies"] = names.nameBodies;
      key["competitor_bodies"] = names.competitorBodies;
      key["target_side"] = names.targetSide;
      key["ask_side"] = names.askSide;
      break;
    }
    case quiz::QuestionKind::Order: {
      // An entry resolves as quiz's grader does: an exact id, else the first structure (in the
      // catalogue's order) whose id or one of whose names normalises to the entry's normal form.
      json ids = json::array(), spellings = json::array();
      for (const quiz::NameEntry& e : context.names) {
        ids.push_back(e.structureId);
        spellings.push_back({quiz::normalizeName(e.structureId), e.structureId});
        for (const std::string& name : e.names) spellings.push_back({quiz::normalizeName(name), e.structureId});
      }
      key["key_order"] = question.keyOrder;
      key["structure_ids"] = ids;
      key["spellings"] = spellings;
      break;
    }
  }
  return key.dump();
}

Result<std::vector<std::string>> courseLessonKeys(const lessons::Course& course, quiz::KeyComputer& keys,
                                                  const quiz::GradingContext& context,
                                                  const std::map<std::string, std::string>& locateViews) {
  std::vector<std::string> out;
  for (const lessons::Lesson& lesson : course.lessons)
    for (const lessons::Step& step : lesson.steps) {
      if (step.kind != lessons::StepKind::Question) continue;
      auto resolved = quiz::resolveQuestion(step.question, keys);
      if (!resolved)
        return tl::unexpected(withContext("the key of question " + step.question.id + " (course " + course.id + ")",
                                          resolved.error()));
      const auto views = locateViews.find(step.question.id);
      out.push_back(lessonKeyJson(*resolved, context, views == locateViews.end() ? "" : views->second));
    }
  return out;
}

Result<int> publishLessonKeys(Database& server, const std::string& code, const std::vector<std::string>& keys,
                              const std::optional<std::string>& by) {
  if (server.backend() != Backend::Postgres)
    return fail("answer keys are published to a class server (postgresql://…), not to the local file " + server.path());
  json all = json::array();
  for (const std::string& k : keys) all.push_back(json::parse(k));
  int published = 0;
  auto status = server.writeTransaction([&](Database& d) -> Status {
    auto call = d.prepare("SELECT at_publish_lesson_keys(?1, ?2, ?3)");
    if (!call) return tl::unexpected(call.error());
    call->bind(1, code).bind(2, all.dump()).bind(3, by.value_or(""));
    auto row = call->step();
    if (!row) return tl::unexpected(serverRefusal(row.error()));
    if (*row) published = call->integer(0);
    return {};
  });
  if (!status) return tl::unexpected(withContext("publishing answer keys to class " + code, status.error()));
  return published;
}

}  // namespace at::db
