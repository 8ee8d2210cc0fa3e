// Course → lessons → steps (ARCHITECTURE.md §5). Plain structs: the JSON loader (course_json.h)
// builds them, db/ stores and returns them, LessonEngine sequences them.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "quiz/question.h"
#include "core/error.h"

namespace at::lessons {

// Camera placements a step can ask for (named from the patient's side the camera looks from).
enum class CameraView { Anterior, Posterior, LateralLeft, LateralRight, Superior, Inferior };
const char* toString(CameraView view);  // "anterior", …, "lateral_left", "lateral_right", …
Result<CameraView> parseCameraView(const std::string& text);

enum class StepKind {
  Show,      // show a structure with a preset, a camera and a text
  Question,  // ask a question
  Study,     // a preference-study comparison (reserved: the engine refuses lessons containing it)
};
const char* toString(StepKind kind);  // "show", "question", "study"
Result<StepKind> parseStepKind(const std::string& text);

struct ShowStep {
  std::string structure;  // structure id in the course's dataset
  std::string presetId;   // e.g. "cochlea_wdt" (WDT context) or "cochlea_bare" (bare structure)
  CameraView view = CameraView::LateralRight;
  std::string title;      // short heading
  std::string text;       // what it is, where, why it matters (first-year students)
};

// Reserved for the preference study (issue: studies). Stored but not run by LessonEngine.
struct StudyStep {
  std::string structure;
  std::vector<std::string> items;  // Likert items, e.g. "showing_shape"
};

struct Step {
  StepKind kind = StepKind::Show;
  ShowStep show;              // Show only
  quiz::Question question;    // Question only
  StudyStep study;            // Study only
};

struct Lesson {
  std::string id;                          // unique across courses: "inner_ear"
  std::string courseId;
  std::string title;
  std::string summary;
  std::vector<std::string> prerequisites;  // lesson ids that must be finished first
  std::vector<Step> steps;
};

struct Course {
  std::string id;          // "temporal_bone"
  std::string title;
  std::string summary;
  std::string datasetId;   // "phantom"
  int version = 1;         // bumped when the content changes (seeding compares it)
  // Extra accepted names per structure id (besides its display name), used by Name questions
  // for the target and to reject answers closer to another structure.
  std::map<std::string, std::vector<std::string>> synonyms;
  std::vector<Lesson> lessons;  // in teaching order
};

}  // namespace at::lessons
