#include "lessons/curriculum.h"
#include "lessons/repositories.h"

namespace at::lessons {

const char* toString(CameraView view) {
  switch (view) {
    case CameraView::Anterior: return "anterior";
    case CameraView::Posterior: return "posterior";
    case CameraView::LateralLeft: return "lateral_left";
    case CameraView::LateralRight: return "lateral_right";
    case CameraView::Superior: return "superior";
    case CameraView::Inferior: return "inferior";
  }
  return "lateral_right";
}

Result<CameraView> parseCameraView(const std::string& text) {
  for (CameraView v : {CameraView::Anterior, CameraView::Posterior, CameraView::LateralLeft, CameraView::LateralRight,
                       CameraView::Superior, CameraView::Inferior}) {
    if (text == toString(v)) return v;
  }
  return fail("unknown view '" + text +
              "' (expected anterior, posterior, lateral_left, lateral_right, superior or inferior)");
}

QuestionScene sceneFor(const Step& step) {
  if (step.scene) {
    QuestionScene scene = *step.scene;
    if (scene.presetId.empty()) scene.presetId = scene.structure + "_wdt";
    return scene;
  }
  const quiz::Question& q = step.question;
  QuestionScene scene;
  scene.structure = q.target;
  switch (q.kind) {
    case quiz::QuestionKind::Relation:
      if (!q.relation.from.empty()) scene.structure = q.relation.from;
      break;
    case quiz::QuestionKind::Order:
      if (!q.order.targetStructure.empty()) scene.structure = q.order.targetStructure;
      break;
    default:
      break;
  }
  scene.presetId = scene.structure + "_wdt";
  return scene;
}

const char* toString(ExamLocateView view) { return view == ExamLocateView::ThreeD ? "3d" : "slice"; }

Result<ExamLocateView> parseExamLocateView(const std::string& text) {
  if (text == "3d") return ExamLocateView::ThreeD;
  if (text == "slice") return ExamLocateView::Slice;
  return fail("unknown locate view '" + text + "' (expected 3d or slice)");
}

const char* toString(StepKind kind) {
  switch (kind) {
    case StepKind::Show: return "show";
    case StepKind::Question: return "question";
    case StepKind::Study: return "study";
  }
  return "show";
}

Result<StepKind> parseStepKind(const std::string& text) {
  for (StepKind k : {StepKind::Show, StepKind::Question, StepKind::Study}) {
    if (text == toString(k)) return k;
  }
  return fail("unknown step kind '" + text + "' (expected show, question or study)");
}

const char* toString(Role role) {
  switch (role) {
    case Role::Student: return "student";
    case Role::Expert: return "expert";
    case Role::Coordinator: return "coordinator";
  }
  return "student";
}

Result<Role> parseRole(const std::string& text) {
  for (Role r : {Role::Student, Role::Expert, Role::Coordinator}) {
    if (text == toString(r)) return r;
  }
  return fail("unknown role '" + text + "' (expected student, expert or coordinator)");
}

const char* toString(LessonMode mode) { return mode == LessonMode::Guided ? "guided" : "quiz_only"; }

Result<LessonMode> parseLessonMode(const std::string& text) {
  if (text == "guided") return LessonMode::Guided;
  if (text == "quiz_only") return LessonMode::QuizOnly;
  return fail("unknown lesson mode '" + text + "' (expected guided or quiz_only)");
}

const char* toString(AnswerSource source) {
  switch (source) {
    case AnswerSource::Lesson: return "lesson";
    case AnswerSource::Review: return "review";
    case AnswerSource::Exam: return "exam";
  }
  return "?";
}

Result<AnswerSource> parseAnswerSource(const std::string& text) {
  for (AnswerSource s : {AnswerSource::Lesson, AnswerSource::Review, AnswerSource::Exam})
    if (text == toString(s)) return s;
  return fail("unknown answer source '" + text + "' (expected lesson, review or exam)");
}

}  // namespace at::lessons
