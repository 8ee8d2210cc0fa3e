// `class keys CODE --db SERVER [--course ID] [--local-db PATH]`: an instructor or coordinator
// publishes the answer keys of the class's courses to the class server, which then grades every
// lesson and review answer itself (db/class_lesson_keys.h): the keys are resolved on this machine,
// which has the courses and their datasets, and no student's login can read them on the server.
// Answers the class sent before are graded when their keys arrive.
#include <nlohmann/json.hpp>

#include "class_exam_cli.h"
#include "commands.h"
#include "core/strings.h"
#include "db/class_lesson_keys.h"
#include "db/class_server.h"
#include "lessons/lesson_engine.h"
#include "printable_output.h"

namespace at::app {

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
  int published = 0;
  for (const lessons::Course& course : courses) {
    auto structures = ls.structures(course.datasetId);
    auto keys = structures ? ls.keysFor(course.datasetId) : tl::unexpected(structures.error());
    if (!structures || !keys) {
      const std::string why = !structures ? structures.error().message : keys.error().message;
      if (args.value("course")) return reportError("class keys: course '" + course.id + "': " + why);
      terminalPrintf("course %s skipped: %s\n", course.id.c_str(), why.c_str());
      continue;
    }
    auto resolved = db::courseLessonKeys(course, **keys, lessons::gradingContext(*structures, course));
    if (!resolved) return reportError("class keys: " + resolved.error().message);
    auto sent = db::publishLessonKeys(*server, *code, *resolved, args.user());
    if (!sent) return reportError("class keys: " + sent.error().message);
    terminalPrintf("course %s: %s published to class %s; its answers are graded on the server\n", course.id.c_str(),
                   str::countOf(*sent, "key").c_str(), code->c_str());
    published += *sent;
  }
  if (published == 0) return reportError("class keys: no course's keys could be published from this machine");
  return 0;
}

}  // namespace at::app
