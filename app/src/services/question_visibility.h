// Whether each locate question of a course can be answered in its own view: the view rendered as
// the terminal draws it (400×300, framed on the region with a margin, the step's preset, camera and
// clip), a click on the target's centre must pick the target. `course validate` refuses a course
// that fails it; tests/app/test_question_scenes.cpp checks the shipped courses with the same code.
#pragma once

#include <string>
#include <vector>

#include "core/error.h"
#include "lessons/curriculum.h"
#include "render/preset.h"
#include "volume/structure.h"

namespace at::app {

// How the check draws a question's view (as app/src/cli/terminal_views.h does).
constexpr int kCheckViewWidth = 400, kCheckViewHeight = 300;
constexpr double kLocateRegionMargin = 2.5;

struct LocateCheck {
  std::string path;        // "lessons[3].steps[4].question"
  std::string questionId;
  bool answerable = false;  // a click on the target's centre picks the target
  std::string problem;      // when not: what the click picks instead, or why it cannot be made
};

// Checks every locate question of `course` on `dataset` (one WDT per region structure, on the CPU).
// Errors: a structure or preset the course names is missing, a field that cannot be computed.
Result<std::vector<LocateCheck>> checkLocateQuestions(const Dataset& dataset, const lessons::Course& course,
                                                      const render::PresetLibrary& presets);

}  // namespace at::app
