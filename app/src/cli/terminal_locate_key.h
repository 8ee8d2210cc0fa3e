// The key of a locate item graded on a class server: which pixels of the item's picture count.
#pragma once

#include <vector>

#include "db/class_exams.h"
#include "quiz/grading.h"
#include "terminal_views.h"

namespace at::app {

// The pixels of `picture` (the one `views` showed last) whose click the laptop's own grader
// (TerminalViews::pickPixel, then quiz::gradeLocate) counts right for `question`, as runs of a row.
// Each pixel is judged at its integer coordinates, as a typed "x y" is picked.
Result<std::vector<db::PixelRun>> acceptedPixelRuns(TerminalViews& views, const TerminalPicture& picture,
                                                    const quiz::ResolvedQuestion& question,
                                                    const quiz::GradingContext& context);

}  // namespace at::app
