// anatomy-tutor exam: a practical exam in the terminal through lessons::ExamSession — labels
// hidden, no feedback until the end, against the exam's clock. Each item's view is written as a PNG
// (a 3-D view, or a CT slice for locate items on slices); answers come from a JSON-lines file or
// are typed. Every answer is saved when given; the results and the score come at the end.
#include <cstdio>
#include <map>

#include "class_exam_cli.h"
#include "cli_args.h"
#include "commands.h"
#include "db/class_server.h"
#include "db/exam_store.h"
#include "core/strings.h"
#include "learning_session.h"
#include "lessons/exam.h"
#include "terminal_answers.h"
#include "terminal_views.h"
#include "printable_output.h"

namespace at::app {

namespace {

constexpr const char* kExamHelp =
    "usage: anatomy-tutor exam EXAM --user NAME [--answers FILE.jsonl] [--new-user [--group GROUP]]\n"
    "                          [--views DIR | --no-views] [--db PATH]\n\n"
    "Takes a practical exam of a course (`anatomy-tutor lessons` lists them): a number of items drawn\n"
    "from the exam's structures — locate it (in a 3-D view or on a CT slice), identify the marked\n"
    "structure, or name it — within the exam's time limit. Labels are hidden and no answer is marked\n"
    "until the end; then every item's result and the score are shown and saved.\n\n"
    "Each item's view is written as a PNG (--views DIR, default ./anatomy-tutor-views). Typed answers:\n"
    "the pixel x y where the structure is in the picture (or mm X Y Z), the number of a choice, a name;\n"
    "'skip' leaves an item for later, 'finish' hands in, 'quit' leaves the exam open (the clock runs on:\n"
    "the same command continues it). With --answers, one JSON answer per item in order (the forms of\n"
    "`anatomy-tutor play --help`); the end of the file hands in.\n";

std::string clock(lessons::UnixSeconds seconds) {
  char text[32];
  std::snprintf(text, sizeof text, "%lld:%02lld", (long long)(seconds / 60), (long long)(seconds % 60));
  return text;
}

struct ExamRun {
  lessons::ExamSession& session;
  AnswerSource& source;
  TerminalViews* views;
  std::map<std::string, std::string> idByName;
  std::map<std::string, std::string> nameById;
};

// Shows item `position` and reads its answer.
Result<Asked> askItem(ExamRun& run, int position) {
  auto item = run.session.item(position);
  if (!item) return tl::unexpected(item.error());
  terminalPrintf("\n[%d/%d] %s left — %s\n", position + 1, item->count, clock(run.session.secondsLeft()).c_str(),
              item->prompt.c_str());
  for (std::size_t i = 0; i < item->choiceNames.size(); ++i) terminalPrintf("    %zu) %s\n", i, item->choiceNames[i].c_str());
  const bool locate = item->kind == quiz::QuestionKind::Locate;
  if (run.views && run.views->pictures()) {
    char stem[200];
    std::snprintf(stem, sizeof stem, "%s-%02d", run.session.exam().id.c_str(), position + 1);
    auto picture = locate && item->locateView == lessons::ExamLocateView::Slice
                       ? run.views->showSlice(item->target, stem)
                       : run.views->show(item->scene, stem, locate, locate ? std::optional<std::string>(item->target)
                                                                           : std::nullopt);
    if (picture)
      terminalPrintf("  %s: %s%s\n", picture->slice ? "slice" : "view", picture->path.c_str(),
                  locate ? "  — answer with the pixel x y where it is" : "");
    else
      terminalPrintf("  (no picture: %s)\n", picture.error().message.c_str());
  }
  std::fflush(stdout);
  AskedQuestion q{item->kind, item->target, item->choiceIds, run.idByName, run.views, std::nullopt};
  return askQuestion(run.source, q,
                     [&](const quiz::Answer& answer, std::int64_t latencyMs) -> Result<std::optional<quiz::Grade>> {
                       lessons::RenderState render;
                       render.presetId = item->scene.presetId;
                       render.mode = "terminal";
                       if (auto st = run.session.answer(position, answer, latencyMs, render); !st)
                         return tl::unexpected(st.error());
                       terminalPrintf("  (saved)\n");
                       return std::optional<quiz::Grade>();
                     },
                     true);
}

// The results and the review: each item, the answer given and the right one, and for an item not
// right its answer's pictures (the target in its own view, and on a slice through it).
void printResults(const lessons::ExamResult& r, const lessons::ExamSpec& exam,
                  const std::map<std::string, std::string>& nameById, TerminalViews* views) {
  terminalPrintf("\n%s\n", r.timeRanOut ? "Time is up." : "Handed in.");
  terminalPrintf("Results: %d of %s right, score %.2f", r.correct, str::countOf(long(r.items.size()), "item").c_str(), r.score);
  if (r.passed) terminalPrintf(" — %s (pass mark %.2f)", *r.passed ? "passed" : "not passed", exam.passScore.value_or(0));
  terminalPrintf("\n");
  for (const lessons::ExamItemResult& x : r.items) {
    const auto name = nameById.count(x.structure) ? nameById.at(x.structure) : x.structure;
    terminalPrintf("  %2d. %s (%s): ", x.position + 1, name.c_str(), quiz::toString(x.kind));
    const std::string mark = !x.answered ? "– " : x.correct ? "✓ " : x.score > 0 ? "◑ " : "✗ ";
    printWrapped(mark + x.feedback, 0);
    terminalPrintf("      you: %s   answer: %s\n", x.answered ? x.yourAnswer.c_str() : "(none)", x.rightAnswer.c_str());
    if (x.correct || !views || !views->pictures()) continue;
    char stem[200];
    std::snprintf(stem, sizeof stem, "%s-review-%02d", exam.id.c_str(), x.position + 1);
    if (auto picture = views->show(x.scene, stem)) terminalPrintf("      view: %s\n", picture->path.c_str());
    else terminalPrintf("      (no picture: %s)\n", picture.error().message.c_str());
    if (auto slice = views->showSlice(x.structure, std::string(stem) + "-slice", true))
      terminalPrintf("      slice: %s\n", slice->path.c_str());
    else terminalPrintf("      (no slice: %s)\n", slice.error().message.c_str());
  }
}

}  // namespace

int runExam(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"answers", "group", "views"}, {"new-user", "no-views"});
  if (!args) return reportError("exam: " + args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s", kExamHelp);
    return 0;
  }
  if (args->positional().size() != 1) return reportError("exam: give exactly one EXAM (see `anatomy-tutor lessons`)");
  if (args->has("views") && args->has("no-views")) return reportError("exam: give --views DIR or --no-views, not both");
  const auto userName = args->user();
  if (!userName) return reportError("exam: --user NAME is required");
  auto source = answerSource(args->value("answers"));
  if (!source) return reportError("exam: " + source.error().message);

  auto learning = LearningSession::open(args->db());
  if (!learning) return reportError("exam: " + learning.error().message);
  LearningSession& ls = **learning;
  db::SqlExamRepository exams(ls.database());
  const std::string examId = args->positional()[0];
  auto found = lessons::findExam(ls.curriculum(), examId);
  if (!found) return reportError("exam: " + found.error().message + " (see `anatomy-tutor lessons`)");
  const lessons::Course& course = found->first;
  auto structures = ls.structures(course.datasetId);
  if (!structures) return reportError("exam: " + structures.error().message);
  bool created = false;
  auto user = ls.user(*userName, args->has("new-user") ? LearningSession::NewUser::Create : LearningSession::NewUser::Refuse,
                      args->valueOr("group", ""), &created);
  if (!user) return reportError("exam: " + user.error().message);
  if (created) terminalPrintf("created user '%s'\n", user->name.c_str());

  // An exam open in the user's class is taken on the class server (graded there).
  if (auto onServer = runServerExam(ls, user->name, examId, **source, args->value("views"), args->has("no-views")))
    return *onServer;

  const std::string datasetId = course.datasetId;
  auto keys = ls.keysFor(datasetId);
  if (!keys) return reportError("exam: " + keys.error().message);
  lessons::ExamSession session(ls.curriculum(), ls.progress(), exams, **keys);
  if (auto started = session.start(user->id, examId); !started) return reportError("exam: " + started.error().message);
  const lessons::ExamSpec& exam = session.exam();

  terminalPrintf("Exam: %s (%s), course %s\n", rowCell(exam.title).c_str(), exam.id.c_str(), rowCell(course.title).c_str());
  terminalPrintf("  %s, %s", str::countOf(session.itemCount(), "item").c_str(), clock(exam.timeLimitS).c_str());
  if (exam.passScore) terminalPrintf(", pass mark %.0f%%", 100 * *exam.passScore);
  terminalPrintf(". Labels are hidden and no answer is marked until you finish.\n");
  // On a laptop the items and their keys are in the learner's own file: for a class, practice.
  if (db::backendOf(ls.database()) == db::Backend::Sqlite)
    if (auto joined = db::membershipOf(ls.database(), user->name); joined && *joined)
      terminalPrintf("  Practice: graded on this machine and not sent to class %s; only an exam the class's instructor\n"
                     "  opened on the class server (class open-exam) counts.\n",
                  (*joined)->classCode.c_str());
  if (!exam.instructions.empty()) printWrapped(exam.instructions, 2);
  if (session.resumed()) {
    int answered = 0;
    for (int i = 0; i < session.itemCount(); ++i) answered += session.item(i)->answered ? 1 : 0;
    terminalPrintf("  Continuing: %d of %d answered, %s left.\n", answered, session.itemCount(),
                clock(session.secondsLeft()).c_str());
  }
  std::fflush(stdout);

  ExamRun run{session, **source, nullptr, structureIdsByName(*structures), {}};
  for (const Structure& s : *structures) run.nameById[s.id] = s.displayName.empty() ? s.id : s.displayName;
  auto views = openTerminalViews(ls.database(), datasetId, args->value("views"), args->has("no-views"));
  run.views = views.get();

  // Unanswered items in order, again and again (skipped ones come back) until every item is
  // answered, the student hands in, or the time is up.
  bool handIn = false;
  while (!handIn && session.secondsLeft() > 0) {
    const auto next = session.nextUnanswered();
    if (!next) break;
    bool answeredAny = false;
    for (int position = *next; position < session.itemCount() && session.secondsLeft() > 0; ++position) {
      if (session.item(position)->answered) continue;
      auto asked = askItem(run, position);
      if (!asked) {
        if (session.secondsLeft() == 0) break;  // the clock ran out while the item was asked
        return reportError("exam: " + asked.error().message + " (earlier answers are saved)");
      }
      if (*asked == Asked::Answered) answeredAny = true;
      if (*asked == Asked::Finish) handIn = true;
      if (*asked == Asked::Quit || (*asked == Asked::InputEnded && (*source)->interactive())) {
        terminalPrintf("\nleft the exam with %s to go; your answers are saved and the clock runs on — run the same "
                    "command to continue\n", clock(session.secondsLeft()).c_str());
        return 0;
      }
      if (*asked == Asked::InputEnded) handIn = true;  // the end of an answers file hands in
      if (handIn) break;
    }
    if (!answeredAny && !handIn && (*source)->interactive()) {
      terminalPrintf("\nEvery item left is skipped; type 'finish' to hand in.\n");
    }
  }
  auto results = session.finish();
  if (!results) return reportError("exam: " + results.error().message);
  printResults(*results, exam, run.nameById, run.views);
  return 0;
}

}  // namespace at::app
