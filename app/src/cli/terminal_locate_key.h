// The key of a locate item graded on a class server: which pixels of the item's picture count.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "db/class_exams.h"
#include "lessons/curriculum.h"
#include "quiz/grading.h"
#include "quiz/keys.h"
#include "terminal_views.h"

namespace at::app {

// The pixels of `picture` (the one `views` showed last) whose click the laptop's own grader
// (TerminalViews::pickPixel, then quiz::gradeLocate) counts right for `question`, as runs of a row.
// Each pixel is judged at its integer coordinates, as a typed "x y" is picked.
Result<std::vector<db::PixelRun>> acceptedPixelRuns(TerminalViews& views, const TerminalPicture& picture,
                                                    const quiz::ResolvedQuestion& question,
                                                    const quiz::GradingContext& context);
// The same, empty when no pixel picks right (every click on the picture is then wrong).
Result<std::vector<db::PixelRun>> pixelRunsOf(TerminalViews& views, const TerminalPicture& picture,
                                              const quiz::ResolvedQuestion& question,
                                              const quiz::GradingContext& context);

// The fixed views of `course`'s lesson locate questions, by question id, as a lesson key's "views"
// (db/class_lesson_keys.h; JSON [{view, width, height, runs: [[y, x_from, x_to], …]}]): the picture
// `play` shows for the question (its scene, framed as a locate question), its id
// (TerminalViews::lastViewId) and the pixels whose click the laptop's grader counts. Works with
// pictures off (nothing is drawn).
Result<std::map<std::string, std::string>> lessonLocateViews(TerminalViews& views, const lessons::Course& course,
                                                             quiz::KeyComputer& keys,
                                                             const quiz::GradingContext& context);

}  // namespace at::app
