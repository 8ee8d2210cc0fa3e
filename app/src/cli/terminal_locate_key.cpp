#include "terminal_locate_key.h"

namespace at::app {

Result<std::vector<db::PixelRun>> acceptedPixelRuns(TerminalViews& views, const TerminalPicture& picture,
                                                    const quiz::ResolvedQuestion& question,
                                                    const quiz::GradingContext& context) {
  std::vector<db::PixelRun> runs;
  for (int y = 0; y < picture.height; ++y) {
    int runStart = -1;
    for (int x = 0; x <= picture.width; ++x) {
      bool right = false;
      if (x < picture.width) {
        auto pick = views.pickPixel(x, y, question.question.target);
        if (!pick) return tl::unexpected(pick.error());
        auto grade = quiz::gradeLocate(question, *pick, context);
        if (!grade) return tl::unexpected(grade.error());
        right = grade->correct;
      }
      if (right && runStart < 0) runStart = x;
      if (!right && runStart >= 0) {
        runs.push_back({y, runStart, x - 1});
        runStart = -1;
      }
    }
  }
  if (runs.empty())
    return fail("no pixel of the picture of locate item '" + question.question.id + "' picks the " +
                question.question.target + ": it cannot be answered right");
  return runs;
}

}  // namespace at::app
