// `class keys CODE --db SERVER [--course ID] [--local-db PATH]`: an instructor or coordinator
// publishes the answer keys of the class's courses to the class server, which then grades every
// lesson and review answer itself (db/class_lesson_keys.h): the keys are resolved on this machine,
// which has the courses and their datasets, and no student's login can read them on the server.
// Answers the class sent before are graded when their keys arrive. A locate question's key holds
// the pixels of the picture `play` shows for it: the server grades a pixel picked there, and keeps
// any other locate answer as practice. `class create` publishes the keys the same way.
#include <nlohmann/json.hpp>

#include "class_exam_cli.h"
#include "commands.h"
#include "core/strings.h"
#include "db/class_lesson_keys.h"
#include "db/class_server.h"
#include "lessons/lesson_engine.h"
#include "printable_output.h"
#include "terminal_locate_key.h"
#include "terminal_views.h"

namespace at::app {

Result<int> publishClassKeys(db::Database& server, const std::string& code, LearningSession& ls,
                             const std::vector<lessons::Course>& courses, const std::optional<std::string>& by,
                             bool stopAtFirstMissing, bool locatePixels) {
  int published = 0;
  for (const lessons::Course& course : courses) {
    auto structures = ls.structures(course.datasetId);
    auto keys = structures ? ls.keysFor(course.datasetId) : tl::unexpected(structures.error());
    if (!structures || !keys) {
      const std::string why = !structures ? structures.error().message : keys.error().message;
      if (stopAtFirstMissing) return fail("course '" + course.id + "': " + why);
      terminalPrintf("course %s: its answer keys were not published (%s); run `anatomy-tutor class keys %s` on a "
                     "machine that has its dataset — until then its answers wait ungraded on the server\n",
                     course.id.c_str(), why.c_str(), code.c_str());
      continue;
    }
    const quiz::GradingContext context = lessons::gradingContext(*structures, course);
    // Locate questions: the pixels of the picture `play` shows, graded on the server from the
    // pixel picked (no picture is drawn here).
    Result<std::map<std::string, std::string>> locate = std::map<std::string, std::string>{};
    if (locatePixels) {
      auto views = TerminalViews::create(ls.database(), course.datasetId, "anatomy-tutor-views", false);
      if (!views) return fail("course '" + course.id + "': " + views.error().message);
      locate = lessonLocateViews(**views, course, **keys, context);
      if (!locate) return tl::unexpected(locate.error());
    }
    auto resolved = db::courseLessonKeys(course, **keys, context, *locate);
    if (!resolved) return tl::unexpected(resolved.error());
    auto sent = db::publishLessonKeys(server, code, *resolved, by);
    if (!sent) return tl::unexpected(sent.error());
    int locateQuestions = 0;
    for (const lessons::Lesson& lesson : course.lessons)
      for (const lessons::Step& step : lesson.steps)
        locateQuestions += step.kind == lessons::StepKind::Question && step.question.kind == quiz::QuestionKind::Locate;
    terminalPrintf("course %s: %s published to class %s; its answers are graded on the server\n", course.id.c_str(),
                   str::countOf(*sent, "key").c_str(), code.c_str());
    if (!locatePixels && locateQuestions > 0)
      terminalPrintf("  its %s stay practice until their pictures' pixels are published: run `anatomy-tutor class "
                     "keys %s --db SERVER` (slower: the pixels of each question's picture are picked)\n",
                     str::countOf(locateQuestions, "locate question").c_str(), code.c_str());
    published += *sent;
  }
  return published;
}

int runClassKeys(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("class keys: give CODE");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class keys: " + code.error().message);
  if (!args.db() || !db::isPostgresUrl(*args.db()))
    return reportError("class keys: --db SERVER (the class server's postgresql:// URL) is required");
  auto learning = LearningSession::open(args.value("local-db"));
  if (!learning) return reportError("class keys: " + learning.error().message);
  LearningSession& ls = **learning;
  std::vector<lessons::Course> courses;
  if (auto one = args.value("course")) {
    auto course = ls.curriculum().course(*one);
    if (!course) return reportError("class keys: " + course.error().message + " (see `anatomy-tutor courses`)");
    courses.push_back(std::move(*course));
  } else {
    auto all = ls.curriculum().courses();
    if (!all) return reportError("class keys: " + all.error().message);
    courses = std::move(*all);
  }
  db::OpenOptions options;
  options.create = false;
  auto server = db::openDatabase(*args.db(), options);
  if (!server) return reportError("class keys: " + server.error().message);
  auto published = publishClassKeys(*server, *code, ls, courses, args.user(), args.value("course").has_value(), true);
  if (!published) return reportError("class keys: " + published.error().message);
  if (*published == 0) return reportError("class keys: no course's keys could be published from this machine");
  return 0;
}

}  // namespace at::app
