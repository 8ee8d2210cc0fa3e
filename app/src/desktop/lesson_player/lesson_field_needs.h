// The distance fields a running lesson will ask for, in the order the student will want them
// (no SDL, GL or ImGui here): what the desktop prefetches while the student reads a step
// (DesktopModel::prefetchLessonFields, FieldView::prefetch).
#pragma once

#include <string>
#include <vector>

#include "lessons/curriculum.h"

namespace at::app {

struct LessonFieldNeed {
  enum class Kind {
    View,       // a step's scene: its structure with its preset, full resolution
    AnswerKey,  // a locate question's target: the field that grades a click off it (wdt/answer_keys.h)
    ShowMe,     // "show me" after a wrong answer: the target in its own WDT view (lessons::showMeScene)
  };
  Kind kind = Kind::View;
  int step = 0;           // index in the lesson's steps
  std::string structure;  // id
  std::string presetId;   // View and ShowMe: "" = "<structure>_wdt"
};

// `current`: the step on screen; `upcoming`: the steps the lesson shows after it, in order
// (LessonEngine::upcomingSteps). Order: the current step's view (it may still be computing), the
// next step's view, then the current question's answer key and show-me field (wanted only after
// the student answers), then for each later step its view, answer key and show-me field. Study
// steps need none. Duplicates are left in; the caller keeps the first of each field.
std::vector<LessonFieldNeed> lessonFieldNeeds(const std::vector<lessons::Step>& steps, int current,
                                              const std::vector<int>& upcoming);

}  // namespace at::app
