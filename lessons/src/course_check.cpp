#include "lessons/course_check.h"

namespace at::lessons {

namespace {

class ReferenceCheck {
 public:
  ReferenceCheck(const Course& course, const std::set<std::string>& ids) : course_(course), ids_(ids) {}

  void operator()(const std::string& path, const std::string& id) {
    if (id.empty() || ids_.count(id)) return;
    problems_.push_back(path + ": no structure '" + id + "' in dataset '" + course_.datasetId + "'");
  }
  void list(const std::string& path, const std::vector<std::string>& ids) {
    for (std::size_t i = 0; i < ids.size(); ++i) (*this)(path + "[" + std::to_string(i) + "]", ids[i]);
  }
  std::vector<std::string> take() { return std::move(problems_); }

 private:
  const Course& course_;
  const std::set<std::string>& ids_;
  std::vector<std::string> problems_;
};

void checkQuestion(ReferenceCheck& check, const std::string& at, const quiz::Question& q) {
  check(at + ".target", q.target);
  check.list(at + ".choices", q.choices);
  check(at + ".relation.from", q.relation.from);
  check.list(at + ".relation.candidates", q.relation.candidates);
  check(at + ".order.entry_structure", q.order.entryStructure);
  check(at + ".order.target_structure", q.order.targetStructure);
}

}  // namespace

std::vector<std::string> unknownStructureReferences(const Course& course, const std::set<std::string>& structureIds) {
  ReferenceCheck check(course, structureIds);
  for (const auto& [structure, names] : course.synonyms) check("synonyms." + structure, structure);
  for (std::size_t li = 0; li < course.lessons.size(); ++li) {
    const Lesson& lesson = course.lessons[li];
    for (std::size_t si = 0; si < lesson.steps.size(); ++si) {
      const Step& step = lesson.steps[si];
      const std::string at = "lessons[" + std::to_string(li) + "].steps[" + std::to_string(si) + "]";
      switch (step.kind) {
        case StepKind::Show: check(at + ".structure", step.show.structure); break;
        case StepKind::Study: check(at + ".structure", step.study.structure); break;
        case StepKind::Question:
          checkQuestion(check, at + ".question", step.question);
          if (step.scene) check(at + ".structure", step.scene->structure);
          break;
      }
    }
  }
  for (std::size_t ei = 0; ei < course.exams.size(); ++ei)
    check.list("exams[" + std::to_string(ei) + "].structures", course.exams[ei].structures);
  return check.take();
}

Status checkStructureReferences(const Course& course, const std::set<std::string>& structureIds, const std::string& source) {
  const std::vector<std::string> problems = unknownStructureReferences(course, structureIds);
  if (problems.empty()) return {};
  std::string message = source + ": " + problems.front();
  if (problems.size() > 1) message += " (and " + std::to_string(problems.size() - 1) + " more)";
  return fail(ErrorKind::Invalid, message);
}

}  // namespace at::lessons
