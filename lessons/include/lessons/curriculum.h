// Course → lessons → steps (ARCHITECTURE.md §5). Plain structs: the JSON loader (course_json.h)
// builds them, db/ stores and returns them, LessonEngine sequences them.
#pragma once

#include <map>
#include <optional>
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

// A free camera a step replays instead of framing its named view (the course's dataset, LPS mm):
// the eye is `distanceMm` from `targetMm`, looking along `look` (unit, eye → target) with `up`
// (unit, orthogonal to `look`) the screen's up. The view's height at the target is fixed by the
// distance, so a wider window shows more at the sides.
struct StepCamera {
  Vec3 targetMm{0, 0, 0};
  Vec3 look{1, 0, 0};
  Vec3 up{0, 0, 1};
  double distanceMm = 100;
  bool operator==(const StepCamera&) const = default;
};

// A clipping plane a step replays (LPS mm): what lies where dot(normal, p) > d is cut away. The
// normal is one patient axis, either way (±x, ±y or ±z), as the desktop's clip control offers.
struct StepClip {
  Vec3 normal{1, 0, 0};
  double d = 0;
  bool operator==(const StepClip&) const = default;
};

struct ShowStep {
  std::string structure;  // structure id in the course's dataset
  std::string presetId;   // e.g. "cochlea_wdt" (WDT context) or "cochlea_bare" (bare structure)
  CameraView view = CameraView::LateralRight;
  std::string title;      // short heading
  std::string text;       // what it is, where, why it matters (first-year students)
  std::optional<StepCamera> camera;  // replaces the named view's framing when set
  std::optional<StepClip> clip;      // none: the step shows the volume unclipped
};

// Reserved for the preference study (issue: studies). Stored but not run by LessonEngine.
struct StudyStep {
  std::string structure;
  std::vector<std::string> items;  // Likert items, e.g. "showing_shape"
};

// What the 3-D view shows while a question is asked: `structure` is selected (its weighted
// distance field drives the context, the view is framed on it), drawn with `presetId` from `view`.
// Identify and name questions select their target (highlighted, its name hidden); a locate
// question selects a neighbouring landmark whose context shows the target without marking it.
struct QuestionScene {
  std::string structure;
  std::string presetId;   // "" = "<structure>_wdt"
  CameraView view = CameraView::LateralRight;
  std::optional<StepCamera> camera;  // as ShowStep's
  std::optional<StepClip> clip;
};

struct Step {
  StepKind kind = StepKind::Show;
  ShowStep show;              // Show only
  quiz::Question question;    // Question only
  std::optional<QuestionScene> scene;  // Question only: as the course sets it (sceneFor fills the default)
  StudyStep study;            // Study only
};

// The scene a question step shows: the course's (its preset defaulting to "<structure>_wdt"), else
// the default for its kind — identify, name and locate: the target; relation: the structure the
// distances are measured from; order: the drilling target structure (or the question's target).
// The course reader requires a scene on locate questions that does not select the target, since
// the default would highlight the answer; only courses built in code can lack one.
QuestionScene sceneFor(const Step& questionStep);

struct Lesson {
  std::string id;                          // unique across courses: "inner_ear"
  std::string courseId;
  std::string title;
  std::string summary;
  std::vector<std::string> prerequisites;  // lesson ids that must be finished first
  std::vector<Step> steps;
};

// A practical exam (data/courses/README.md): `count` items drawn from every structure × kind pair,
// each structure before any repeats, answered with labels hidden, no feedback until the end, within
// the time limit.
enum class ExamLocateView { ThreeD, Slice };
const char* toString(ExamLocateView view);  // "3d", "slice"
Result<ExamLocateView> parseExamLocateView(const std::string& text);

struct ExamSpec {
  std::string id;                          // unique across courses' lessons and exams: "temporal_bone.practical"
  std::string title;
  std::string instructions;                // shown before the first item
  std::vector<std::string> structures;     // structure ids examined
  std::vector<quiz::QuestionKind> kinds;   // locate, identify, name
  int count = 0;                           // items per attempt, 1..structures × kinds
  int timeLimitS = 0;                      // > 0
  std::vector<ExamLocateView> locateViews{ExamLocateView::ThreeD};  // where locate items are answered
  std::optional<double> passScore;         // 0..1: the mean item score needed to pass
  std::vector<std::string> prerequisites;  // lesson ids to finish before the exam
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
  std::vector<ExamSpec> exams;
};

}  // namespace at::lessons
