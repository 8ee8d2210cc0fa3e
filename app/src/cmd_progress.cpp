// The learning commands that only read: `courses`, `lessons [COURSE]` and `progress --user NAME`.
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <map>

#include "cli_args.h"
#include "commands.h"
#include "learning_support.h"
#include "lessons/lesson_engine.h"
#include "lessons/scheduling.h"

namespace at::app {

namespace {

std::string relativeTime(lessons::UnixSeconds at, lessons::UnixSeconds now) {
  const long long d = at - now;
  if (d <= 0) return "due now";
  if (d < 3600) return "in " + std::to_string((d + 59) / 60) + " min";
  if (d < 86400) return "in " + std::to_string((d + 3599) / 3600) + " h";
  return "in " + std::to_string((d + 86399) / 86400) + " days";
}

int questionCount(const lessons::Lesson& l) {
  return int(std::count_if(l.steps.begin(), l.steps.end(),
                           [](const lessons::Step& s) { return s.kind == lessons::StepKind::Question; }));
}

}  // namespace

int runCourses(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"db"}, {});
  if (!args) return reportError("courses: " + args.error().message);
  if (args->has("help")) {
    std::printf("usage: anatomy-tutor courses [--db PATH]\n\nLists the courses (the default course is added on first run).\n");
    return 0;
  }
  if (!args->positional().empty()) return reportError("courses: unexpected argument '" + args->positional()[0] + "'");
  auto database = openLearningDatabase(args->value("db"), true);
  if (!database) return reportError("courses: " + database.error().message);
  db::SqliteCurriculumRepository curriculum(*database, builtinStructures());
  auto courses = curriculum.courses();
  if (!courses) return reportError("courses: " + courses.error().message);
  for (const auto& c : *courses)
    std::printf("%-24s %-44s dataset %-12s %zu lessons (version %d)\n", c.id.c_str(), c.title.c_str(),
                c.datasetId.c_str(), c.lessons.size(), c.version);
  return 0;
}

int runLessons(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"db"}, {});
  if (!args) return reportError("lessons: " + args.error().message);
  if (args->has("help")) {
    std::printf("usage: anatomy-tutor lessons [COURSE] [--db PATH]\n\n"
                "Lists the lessons of every course (or of COURSE) in teaching order, with their\n"
                "prerequisites. `anatomy-tutor play LESSON --user NAME` runs one.\n");
    return 0;
  }
  if (args->positional().size() > 1) return reportError("lessons: give at most one COURSE");
  auto database = openLearningDatabase(args->value("db"), true);
  if (!database) return reportError("lessons: " + database.error().message);
  db::SqliteCurriculumRepository curriculum(*database, builtinStructures());
  std::vector<lessons::Course> courses;
  if (args->positional().empty()) {
    auto all = curriculum.courses();
    if (!all) return reportError("lessons: " + all.error().message);
    courses = std::move(*all);
  } else {
    auto one = curriculum.course(args->positional()[0]);
    if (!one) return reportError("lessons: " + one.error().message + " (see `anatomy-tutor courses`)");
    courses.push_back(std::move(*one));
  }
  for (const auto& c : courses) {
    std::printf("%s — %s\n", c.id.c_str(), c.title.c_str());
    for (const auto& l : c.lessons) {
      std::printf("  %-28s %-40s %2zu steps, %d questions", l.id.c_str(), l.title.c_str(), l.steps.size(),
                  questionCount(l));
      if (!l.prerequisites.empty()) {
        std::printf("  after:");
        for (const auto& p : l.prerequisites) std::printf(" %s", p.c_str());
      }
      std::printf("\n");
    }
  }
  return 0;
}

int runProgress(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"user", "db"}, {});
  if (!args) return reportError("progress: " + args.error().message);
  if (args->has("help")) {
    std::printf("usage: anatomy-tutor progress --user NAME [--db PATH]\n\n"
                "Shows a user's lessons, per-structure progress and the structures due for review now.\n"
                "Per structure: answers given (lesson and review answers alike), how many were right,\n"
                "the predicted chance of recalling it now, and when it is next due. Reviews are\n"
                "scheduled with FSRS-6 so that each structure comes back when that chance falls to 90%%.\n");
    return 0;
  }
  if (!args->positional().empty()) return reportError("progress: unexpected argument '" + args->positional()[0] + "'");
  const auto userName = args->value("user");
  if (!userName || userName->empty()) return reportError("progress: --user NAME is required");
  auto database = openLearningDatabase(args->value("db"), true);
  if (!database) return reportError("progress: " + database.error().message);
  db::SqliteCurriculumRepository curriculum(*database, builtinStructures());
  db::SqliteProgressRepository progress(*database);
  db::SqliteUserRepository users(*database);

  auto user = users.findUser(*userName);
  if (!user) return reportError("progress: " + user.error().message);
  if (!*user) return reportError("progress: unknown user '" + *userName + "'");
  const std::int64_t userId = (*user)->id;
  const lessons::UnixSeconds now = std::time(nullptr);

  auto courses = curriculum.courses();
  if (!courses) return reportError("progress: " + courses.error().message);
  auto attempts = progress.attempts(userId);
  if (!attempts) return reportError("progress: " + attempts.error().message);
  auto all = progress.allProgress(userId);
  if (!all) return reportError("progress: " + all.error().message);
  auto ability = progress.ability(userId);
  if (!ability) return reportError("progress: " + ability.error().message);

  auto reviews = progress.reviewResponses(userId);
  if (!reviews) return reportError("progress: " + reviews.error().message);

  // Lesson and review answers alike: both move the per-structure counts.
  int answered = 0, correct = 0;
  for (const auto& p : *all) {
    answered += p.answered;
    correct += p.correct;
  }
  std::printf("%s (%s%s%s): %d answers, %d correct", (*user)->name.c_str(), lessons::toString((*user)->role),
              (*user)->group.empty() ? "" : ", group ", (*user)->group.c_str(), answered, correct);
  if (!reviews->empty()) {
    const auto right = std::count_if(reviews->begin(), reviews->end(), [](const lessons::ReviewResponse& r) { return r.correct; });
    std::printf(" (%zu in review, %ld correct)", reviews->size(), long(right));
  }
  if (*ability) std::printf(", ability %.0f", **ability);
  std::printf("\n");

  // Display names of every structure the courses use.
  std::map<std::string, std::string> names;
  for (const auto& c : *courses) {
    auto structures = curriculum.structures(c.datasetId);
    if (!structures) continue;  // a course on a dataset not imported here: ids are shown instead
    for (const auto& s : *structures) names.emplace(s.id, s.displayName);
  }

  std::printf("\nLessons\n");
  for (const auto& c : *courses) {
    for (const auto& l : c.lessons) {
      int tries = 0;
      double best = -1;
      bool open = false;
      for (const auto& a : *attempts) {
        if (a.lessonId != l.id) continue;
        ++tries;
        if (a.finishedAt) best = std::max(best, a.score);
        else open = true;
      }
      std::string state = "not started";
      if (best >= 0) {
        char buffer[64];
        std::snprintf(buffer, sizeof buffer, "finished, best score %.2f", best);
        state = buffer;
      }
      if (open) state = best >= 0 ? state + "; another attempt in progress" : "in progress (play resumes it)";
      std::printf("  %-28s %-40s %s (%d attempt%s)\n", l.id.c_str(), l.title.c_str(), state.c_str(), tries,
                  tries == 1 ? "" : "s");
    }
  }

  std::printf("\nStructures\n");
  if (all->empty()) std::printf("  none answered yet\n");
  else std::printf("  %-32s %9s %8s %11s  %s\n", "structure", "answered", "correct", "recall now", "next review");
  const lessons::Fsrs fsrs;
  for (const auto& p : *all) {
    auto it = names.find(p.structureId);
    const std::string name = it == names.end() ? p.structureId : it->second;
    std::printf("  %-32s %9d %8d %10.0f%%  %s\n", name.c_str(), p.answered, p.correct,
                100.0 * fsrs.retrievability(p.memory, now), relativeTime(p.memory.due, now).c_str());
  }

  auto due = lessons::reviewQueue(progress, userId, now);
  if (!due) return reportError("progress: " + due.error().message);
  std::printf("\nDue for review now: ");
  if (due->empty()) std::printf("nothing\n");
  for (std::size_t i = 0; i < due->size(); ++i) {
    auto it = names.find((*due)[i].structureId);
    std::printf("%s%s", i ? ", " : "", it == names.end() ? (*due)[i].structureId.c_str() : it->second.c_str());
    if (i + 1 == due->size()) std::printf("\n");
  }
  return 0;
}

}  // namespace at::app
