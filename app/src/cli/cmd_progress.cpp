// The learning commands that only read: `courses`, `lessons [COURSE]` and `progress --user NAME`.
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <map>

#include "cli_args.h"
#include "commands.h"
#include "core/strings.h"
#include "db/exam_store.h"
#include "learning_session.h"
#include "lessons/lesson_engine.h"
#include "lessons/scheduling.h"
#include "quiz/elo.h"
#include "printable_output.h"

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
  auto args = cli::Args::parse(argv, {}, {});
  if (!args) return reportError("courses: " + args.error().message);
  if (args->has("help")) {
    terminalPrintf("usage: anatomy-tutor courses [--db PATH]\n\nLists the courses (the default course is added on first run).\n");
    return 0;
  }
  if (!args->positional().empty()) return reportError("courses: unexpected argument '" + args->positional()[0] + "'");
  auto session = LearningSession::open(args->db(), true);
  if (!session) return reportError("courses: " + session.error().message);
  auto courses = (*session)->curriculum().courses();
  if (!courses) return reportError("courses: " + courses.error().message);
  for (const auto& c : *courses)
    terminalPrintf("%-24s %-44s dataset %-12s %s%s (version %d)\n", rowCell(c.id).c_str(), rowCell(c.title).c_str(),
                   rowCell(c.datasetId).c_str(),
                str::countOf(long(c.lessons.size()), "lesson").c_str(),
                c.exams.empty() ? "" : (", " + str::countOf(long(c.exams.size()), "exam")).c_str(), c.version);
  return 0;
}

int runLessons(const Argv& argv) {
  auto args = cli::Args::parse(argv, {}, {});
  if (!args) return reportError("lessons: " + args.error().message);
  if (args->has("help")) {
    terminalPrintf("usage: anatomy-tutor lessons [COURSE] [--db PATH]\n\n"
                "Lists the lessons of every course (or of COURSE) in teaching order, with their\n"
                "prerequisites. `anatomy-tutor play LESSON --user NAME` runs one.\n");
    return 0;
  }
  if (args->positional().size() > 1) return reportError("lessons: give at most one COURSE");
  auto session = LearningSession::open(args->db(), true);
  if (!session) return reportError("lessons: " + session.error().message);
  lessons::CurriculumRepository& curriculum = (*session)->curriculum();
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
    terminalPrintf("%s — %s\n", rowCell(c.id).c_str(), rowCell(c.title).c_str());
    for (const auto& l : c.lessons) {
      terminalPrintf("  %-28s %-40s %s, %s", rowCell(l.id).c_str(), rowCell(l.title).c_str(), str::countOf(long(l.steps.size()), "step").c_str(),
                  str::countOf(questionCount(l), "question").c_str());
      if (!l.prerequisites.empty()) {
        terminalPrintf("  after:");
        for (const auto& p : l.prerequisites) terminalPrintf(" %s", rowCell(p).c_str());
      }
      terminalPrintf("\n");
    }
    for (const auto& e : c.exams) {
      terminalPrintf("  %-28s %-40s %s, %d min  (exam)", rowCell(e.id).c_str(), rowCell(e.title).c_str(), str::countOf(e.count, "item").c_str(),
                  (e.timeLimitS + 59) / 60);
      if (!e.prerequisites.empty()) {
        terminalPrintf("  after:");
        for (const auto& p : e.prerequisites) terminalPrintf(" %s", rowCell(p).c_str());
      }
      terminalPrintf("\n");
    }
  }
  return 0;
}

int runProgress(const Argv& argv) {
  auto args = cli::Args::parse(argv, {}, {});
  if (!args) return reportError("progress: " + args.error().message);
  if (args->has("help")) {
    terminalPrintf("usage: anatomy-tutor progress --user NAME [--db PATH]\n\n"
                "Shows a user's lessons, per-structure progress and the structures due for review now.\n"
                "Per structure: answers given (lesson and review answers alike), how many were right,\n"
                "the predicted chance of recalling it now, and when it is next due. Reviews are\n"
                "scheduled with FSRS-6 so that each structure comes back when that chance falls to 90%%.\n");
    return 0;
  }
  if (!args->positional().empty()) return reportError("progress: unexpected argument '" + args->positional()[0] + "'");
  const auto userName = args->user();
  if (!userName) return reportError("progress: --user NAME is required");
  auto session = LearningSession::open(args->db(), true);
  if (!session) return reportError("progress: " + session.error().message);
  lessons::CurriculumRepository& curriculum = (*session)->curriculum();
  lessons::ProgressRepository& progress = (*session)->progress();
  auto found = (*session)->users().findUser(*userName);
  if (!found) return reportError("progress: " + found.error().message);
  if (!*found) return reportError("progress: unknown user '" + *userName + "'");
  const lessons::User* user = &**found;
  const std::int64_t userId = user->id;
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
  terminalPrintf("%s (%s%s%s): %s, %d correct", user->name.c_str(), lessons::toString(user->role),
              user->group.empty() ? "" : ", group ", user->group.c_str(), str::countOf(answered, "answer").c_str(), correct);
  if (!reviews->empty()) {
    const auto right = std::count_if(reviews->begin(), reviews->end(), [](const lessons::ReviewResponse& r) { return r.correct; });
    terminalPrintf(" (%zu in review, %ld correct)", reviews->size(), long(right));
  }
  // The Elo ability as what it predicts: the chance of answering a question of average difficulty.
  if (*ability) terminalPrintf("; expected to get %.0f%% of average questions right", 100 * quiz::expectedScore(**ability, 1500));
  terminalPrintf("\n");

  // Display names of every structure the courses use.
  std::map<std::string, std::string> names;
  for (const auto& c : *courses) {
    auto structures = curriculum.structures(c.datasetId);
    if (!structures) continue;  // a course on a dataset not imported here: ids are shown instead
    for (const auto& s : *structures) names.emplace(s.id, s.displayName);
  }

  terminalPrintf("\nLessons\n");
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
      if (open) state = best >= 0 ? state + "; another attempt in progress" : "in progress, play resumes it";
      if (tries > 0) state += " (" + str::countOf(tries, "attempt") + ")";
      terminalPrintf("  %-28s %-40s %s\n", l.id.c_str(), rowCell(l.title).c_str(), state.c_str());
    }
  }

  // Exams: the latest attempt at each, with its score once handed in.
  db::SqlExamRepository exams((*session)->database());
  auto examAttempts = exams.examAttempts(userId);
  if (!examAttempts) return reportError("progress: " + examAttempts.error().message);
  bool examHeading = false;
  for (const auto& c : *courses)
    for (const auto& e : c.exams) {
      const auto latest = std::find_if(examAttempts->begin(), examAttempts->end(),
                                       [&](const lessons::ExamAttempt& a) { return a.examId == e.id; });
      if (latest == examAttempts->end()) continue;
      if (!examHeading) terminalPrintf("\nExams\n");
      examHeading = true;
      std::string state = "in progress (`anatomy-tutor exam " + e.id + "` continues it while time is left)";
      if (latest->finishedAt) {
        char buffer[96];
        std::snprintf(buffer, sizeof buffer, "score %.2f%s", latest->score,
                      latest->passed ? (*latest->passed ? ", passed" : ", not passed") : "");
        state = buffer;
      }
      const auto tries = std::count_if(examAttempts->begin(), examAttempts->end(),
                                       [&](const lessons::ExamAttempt& a) { return a.examId == e.id; });
      terminalPrintf("  %-28s %-40s %s (%s)\n", e.id.c_str(), rowCell(e.title).c_str(), state.c_str(),
                  str::countOf(tries, "attempt").c_str());
    }

  terminalPrintf("\nStructures\n");
  if (all->empty()) terminalPrintf("  none answered yet\n");
  else terminalPrintf("  %-32s %9s %8s %11s  %s\n", "structure", "answered", "correct", "recall now", "next review");
  const lessons::Fsrs fsrs;
  for (const auto& p : *all) {
    auto it = names.find(p.structureId);
    const std::string name = it == names.end() ? p.structureId : it->second;
    // In its (re)learning steps a structure comes back within minutes; a recall figure in whole
    // days (FSRS's) would read 100% there, so the phase is shown instead.
    char recall[16];
    if (p.memory.phase == lessons::MemoryPhase::Review)
      std::snprintf(recall, sizeof recall, "%.0f%%", 100.0 * fsrs.retrievability(p.memory, now));
    else
      std::snprintf(recall, sizeof recall, "learning");
    terminalPrintf("  %-32s %9d %8d %11s  %s\n", name.c_str(), p.answered, p.correct, recall,
                relativeTime(p.memory.due, now).c_str());
  }

  // The one definition of what is due (lessons::reviewQueue): taught structures only, per course,
  // exactly what `play --review COURSE` and the desktop's review ask about.
  std::vector<std::string> dueLines;
  for (const auto& c : *courses) {
    auto due = lessons::reviewQueue(curriculum, progress, userId, c.id, now);
    if (!due) return reportError("progress: " + due.error().message);
    if (due->empty()) continue;
    std::string list;
    for (const auto& p : *due) {
      auto it = names.find(p.structureId);
      list += (list.empty() ? "" : ", ") + (it == names.end() ? p.structureId : it->second);
    }
    dueLines.push_back(c.id + ": " + str::countOf(int(due->size()), "structure") + " (" + list + ") — `anatomy-tutor play --review " +
                       c.id + " --user " + user->name + "`");
  }
  terminalPrintf("\nDue for review now:%s\n", dueLines.empty() ? " nothing" : "");
  for (const auto& line : dueLines) terminalPrintf("  %s\n", line.c_str());
  return 0;
}

}  // namespace at::app
