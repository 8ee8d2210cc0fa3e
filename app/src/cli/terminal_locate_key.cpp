#include "terminal_locate_key.h"

#include <algorithm>
#include <optional>

#include <nlohmann/json.hpp>

#include "core/parallel_rows.h"

namespace at::app {

Result<std::vector<db::PixelRun>> pixelRunsOf(TerminalViews& views, const TerminalPicture& picture,
                                              const quiz::ResolvedQuestion& question,
                                              const quiz::GradingContext& context) {
  // Only pixels whose pick can reach the target (or its tolerance) are tried; the others are wrong.
  const auto box = picture.slice ? std::nullopt
                                 : views.pixelsThatCanPick(question.question.target, question.question.toleranceMm);
  const int x0 = box ? std::max(0, (*box)[0]) : 0, y0 = box ? std::max(0, (*box)[1]) : 0;
  const int x1 = box ? std::min(picture.width - 1, (*box)[2]) : picture.width - 1;
  const int y1 = box ? std::min(picture.height - 1, (*box)[3]) : picture.height - 1;
  auto picks = views.pixelPicks(question.question.target);
  if (!picks) return tl::unexpected(picks.error());
  // The rows on all cores, each row's runs (or its first error) kept apart and gathered in order.
  const int rows = std::max(0, y1 - y0 + 1);
  std::vector<std::vector<db::PixelRun>> rowRuns(static_cast<std::size_t>(rows));
  std::vector<std::optional<Error>> rowErrors(static_cast<std::size_t>(rows));
  forEachRowInParallel(rows, [&](int row) {
    const int y = y0 + row;
    int runStart = -1;
    for (int x = x0; x <= x1 + 1; ++x) {
      bool right = false;
      if (x <= x1) {
        auto pick = picks->at(x, y);
        if (!pick) {
          rowErrors[std::size_t(row)] = pick.error();
          return;
        }
        auto grade = quiz::gradeLocate(question, *pick, context);
        if (!grade) {
          rowErrors[std::size_t(row)] = grade.error();
          return;
        }
        right = grade->correct;
      }
      if (right && runStart < 0) runStart = x;
      if (!right && runStart >= 0) {
        rowRuns[std::size_t(row)].push_back({y, runStart, x - 1});
        runStart = -1;
      }
    }
  });
  std::vector<db::PixelRun> runs;
  for (int row = 0; row < rows; ++row) {
    if (rowErrors[std::size_t(row)]) return tl::unexpected(*rowErrors[std::size_t(row)]);
    runs.insert(runs.end(), rowRuns[std::size_t(row)].begin(), rowRuns[std::size_t(row)].end());
  }
  return runs;
}

Result<std::vector<db::PixelRun>> acceptedPixelRuns(TerminalViews& views, const TerminalPicture& picture,
                                                    const quiz::ResolvedQuestion& question,
                                                    const quiz::GradingContext& context) {
  auto runs = pixelRunsOf(views, picture, question, context);
  if (runs && runs->empty())
    return fail("no pixel of the picture of locate item '" + question.question.id + "' picks the " +
                question.question.target + ": it cannot be answered right");
  return runs;
}

Result<std::map<std::string, std::string>> lessonLocateViews(TerminalViews& views, const lessons::Course& course,
                                                             quiz::KeyComputer& keys,
                                                             const quiz::GradingContext& context) {
  std::map<std::string, std::string> out;
  for (const lessons::Lesson& lesson : course.lessons)
    for (const lessons::Step& step : lesson.steps) {
      if (step.kind != lessons::StepKind::Question || step.question.kind != quiz::QuestionKind::Locate) continue;
      const std::string where = "question " + step.question.id + " (course " + course.id + ")";
      auto resolved = quiz::resolveQuestion(step.question, keys);
      if (!resolved) return tl::unexpected(withContext("the key of " + where, resolved.error()));
      auto picture = views.frame(lessons::sceneFor(step), true);  // as `play` shows a locate question
      if (!picture) return tl::unexpected(withContext("the picture of " + where, picture.error()));
      auto runs = pixelRunsOf(views, *picture, *resolved, context);
      if (!runs) return tl::unexpected(withContext("the pixels of " + where, runs.error()));
      nlohmann::json list = nlohmann::json::array();
      for (const db::PixelRun& r : *runs) list.push_back({r.y, r.xFrom, r.xTo});
      out[step.question.id] = nlohmann::json::array({nlohmann::json{{"view", views.lastViewId()},
                                                                     {"width", picture->width},
                                                                     {"height", picture->height},
                                                                     {"runs", std::move(list)}}})
                                  .dump();
    }
  return out;
}

}  // namespace at::app
