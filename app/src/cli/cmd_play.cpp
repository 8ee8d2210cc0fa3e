// anatomy-tutor play: one lesson in the terminal through the LessonEngine, or (--review COURSE)
// the course's review questions through lessons::answerReview. Each step's view is written as a
// PNG (terminal_views.h) and its path printed; answers come from a JSON-lines file (--answers) or
// are typed (terminal_answers.h). Every answer is committed to the database before its feedback is
// printed, so an interrupted lesson resumes at the next step.
#include <cstdio>
#include <ctime>
#include <iostream>
#include <map>
#include <unistd.h>

#include "class_practice.h"
#include "class_sync.h"
#include "cli_args.h"
#include "commands.h"
#include "core/strings.h"
#include "learning_session.h"
#include "lessons/lesson_engine.h"
#include "lessons/review_session.h"
#include "terminal_answers.h"
#include "terminal_views.h"
#include "printable_output.h"

namespace at::app {

namespace {

constexpr const char* kPlayHelp =
    "usage: anatomy-tutor play LESSON --user NAME [--answers FILE.jsonl] [--quiz-only]\n"
    "                          [--new-user [--group GROUP]] [--views DIR | --no-views] [--db PATH]\n"
    "       anatomy-tutor play --review COURSE --user NAME [--answers FILE.jsonl] [--views DIR | --no-views] [--db PATH]\n\n"
    "Runs a lesson in the terminal: prints each step, writes the view it refers to as a PNG (and\n"
    "prints its path), asks its questions and grades the answers. Every answer is saved before the\n"
    "next step is shown; running the same command again after an interruption resumes there.\n"
    "For a user who joined a class (`anatomy-tutor class join`), answers are also sent to the class\n"
    "server; while it cannot be reached they wait in the database and go when it is back.\n\n"
    "With --review, asks the course's review questions instead: the structures you have been taught\n"
    "in lessons you started that are due again (scheduled by FSRS so that each comes back when your\n"
    "predicted recall falls to 90%), until none is due or the answers end.\n\n"
    "Typed answers: the number of a choice; a name; structures separated by commas (order); for a\n"
    "locate question the pixel where the structure is in its picture, as x y (e.g. 180 135), or a\n"
    "point in millimetres as mm X Y Z. An empty line shows what to type; 'quit' stops and saves;\n"
    "'back' goes to the previous step (an answered question shows its answer and feedback again).\n"
    "  --answers    one JSON object per line answering the questions from the current one on:\n"
    "                 {\"choice\": 2}  index of a listed choice (they are printed numbered from 0)\n"
    "                 {\"text\": \"cochlea\"}  a typed name\n"
    "                 {\"pixel\": [180, 135]}  a pick on the question's picture (locate)\n"
    "                 {\"point_mm\": [1.5, -2, 0]}  a pick at a point in LPS millimetres (locate)\n"
    "                 {\"pick\": \"stapes\", \"distance_mm\": 0.3}  the structure clicked (scripts)\n"
    "                 {\"order\": [\"a\", \"b\"]}  structures in the order met\n"
    "               blank lines are skipped; a malformed line stops the run with its line number.\n"
    "               Answers from a file are recorded as untimed.\n"
    "  --quiz-only  questions only, without the teaching steps; labels and names hidden\n"
    "  --views      folder for the pictures (default ./anatomy-tutor-views); --no-views: none\n"
    "  --new-user   create the pseudonymous user NAME if it does not exist (with --group)\n"
    "  --db         database file (default: $XDG_DATA_HOME/anatomy-tutor/anatomy-tutor.db)\n";

// Writes the picture of `scene` and prints its path (or why there is none).
void showPicture(TerminalViews* views, const lessons::QuestionScene& scene, const std::string& stem, bool locate) {
  if (!views || !views->pictures()) return;
  auto picture = views->show(scene, stem, locate);
  if (!picture) {
    terminalPrintf("  (no picture: %s)\n", picture.error().message.c_str());
    return;
  }
  terminalPrintf("  view: %s%s\n", picture->path.c_str(),
              locate ? "  — answer with the pixel x y where it is in this picture" : "");
}

// The answer's slice: the target highlighted on the axial CT slice through it.
void showAnswerSlice(TerminalViews* views, const std::string& target, const std::string& stem) {
  if (!views || !views->pictures() || target.empty()) return;
  auto picture = views->showSlice(target, stem, true);
  if (picture) terminalPrintf("  slice: %s\n", picture->path.c_str());
  else terminalPrintf("  (no slice: %s)\n", picture.error().message.c_str());
}

// "Show me" after a wrong answer: the answer highlighted in its own view (lessons::showMeScene)
// and on a slice through it.
void showAnswerIfWrong(const lessons::LessonEngine& engine, TerminalViews* views, const std::string& questionId,
                       const std::string& stem) {
  for (const lessons::QuestionOutcome& o : engine.outcomes()) {
    if (o.questionId != questionId || !o.grade || o.grade->correct) continue;
    terminalPrintf("  the answer: %s\n", o.rightAnswer.c_str());
    showPicture(views, o.scene, stem + "-answer", false);
    showAnswerSlice(views, o.target, stem + "-answer-slice");
  }
}

// The end-of-lesson review: each question, the answer given and the right one (with its picture).
void printLessonReview(const lessons::LessonEngine& engine, TerminalViews* views, const std::string& lessonId) {
  const std::vector<lessons::QuestionOutcome> outcomes = engine.outcomes();
  if (outcomes.empty()) return;
  terminalPrintf("\nReview:\n");
  for (const lessons::QuestionOutcome& o : outcomes) {
    const char* mark = !o.grade ? "-" : o.grade->correct ? "right" : o.grade->score > 0 ? "partly" : "wrong";
    terminalPrintf("  [%d] %s  (%s)\n", o.position, o.prompt.c_str(), mark);
    terminalPrintf("      you: %s   answer: %s\n", o.yourAnswer.empty() ? "(none)" : o.yourAnswer.c_str(),
                o.rightAnswer.c_str());
    if (o.grade && !o.grade->correct) {
      char stem[160];
      std::snprintf(stem, sizeof stem, "%s-review-%02d", lessonId.c_str(), o.position);
      showPicture(views, o.scene, stem, false);
      showAnswerSlice(views, o.target, std::string(stem) + "-slice");
    }
  }
}

void printQuestion(const std::string& heading, quiz::QuestionKind kind, const std::string& prompt,
                   const std::vector<std::string>& choiceNames) {
  terminalPrintf("\n%s Question (%s)\n", heading.c_str(), quiz::toString(kind));
  printWrapped(prompt, 2);
  for (std::size_t i = 0; i < choiceNames.size(); ++i) terminalPrintf("    %zu) %s\n", i, choiceNames[i].c_str());
}

// What `play` shows on a terminal: its pictures use the step's preset at the default t, α, β.
lessons::RenderState terminalRender(const lessons::QuestionScene& scene) {
  lessons::RenderState render;
  render.presetId = scene.presetId;
  render.mode = "terminal";
  return render;
}

struct PlayContext {
  LearningSession& session;
  lessons::CurriculumRepository& curriculum;
  lessons::ProgressRepository& progress;
  AnswerSource& source;
  std::int64_t userId = 0;
  std::optional<std::string> viewsDir;
  bool noViews = false;
  OutboxSender* classEvents = nullptr;  // sends the user's answers to their class server
  bool classMember = false;             // ... which the user joined (answersGoToClassServer)
};

// Sends what waits for the class server (`now`: whatever the last failure), printing a line when
// the server went away or came back.
void sendClassEvents(PlayContext& ctx, bool now = false) {
  if (!ctx.classEvents) return;
  const std::string line = now ? ctx.classEvents->sendNow() : ctx.classEvents->sendWaiting();
  if (!line.empty()) terminalPrintf("  (%s)\n", line.c_str());
}

// A locate pick that is not a pixel on the question's picture (a point in mm) is practice on a
// class server (class_practice.h): a student whose answers go to one is told so.
void notePracticePick(const PlayContext& ctx, const quiz::Answer& answer) {
  if (ctx.classMember && answer.pick && !classServerGrades(*answer.pick))
    terminalPrintf("  (%s)\n", practicePickNote().c_str());
}

// play --review COURSE: review questions until nothing is due or the answers end.
int runReview(const std::string& courseId, PlayContext& ctx) {
  auto course = ctx.curriculum.course(courseId);
  if (!course) return reportError("play: " + course.error().message + " (see `anatomy-tutor courses`)");
  auto structures = ctx.session.structures(course->datasetId);
  if (!structures) return reportError("play: " + structures.error().message);
  std::map<std::string, std::string> nameById;
  for (const Structure& s : *structures) nameById[s.id] = s.displayName.empty() ? s.id : s.displayName;
  const std::string datasetId = course->datasetId;
  auto keysFound = ctx.session.keysFor(datasetId);
  if (!keysFound) return reportError("play: " + keysFound.error().message);
  quiz::KeyComputer& keys = **keysFound;

  terminalPrintf("Review: %s (%s)\n", rowCell(course->title).c_str(), courseId.c_str());
  {
    const auto now = lessons::UnixSeconds(std::time(nullptr));
    auto taught = lessons::taughtStructures(ctx.curriculum, ctx.progress, ctx.userId, courseId);
    if (!taught) return reportError("play: " + taught.error().message);
    auto due = lessons::reviewQueue(ctx.curriculum, ctx.progress, ctx.userId, courseId, now);
    if (!due) return reportError("play: " + due.error().message);
    if (taught->empty()) {
      terminalPrintf("Review asks about what you have been taught; nothing of this course yet. Start with a lesson\n"
                  "(`anatomy-tutor lessons %s`, then `anatomy-tutor play LESSON --user NAME`).\n", courseId.c_str());
    } else if (!due->empty()) {
      std::string list;
      for (const auto& p : *due) list += (list.empty() ? "" : ", ") + nameById[p.structureId];
      terminalPrintf("Due now: %s (%s)\n", str::countOf(long(due->size()), "structure").c_str(), list.c_str());
    }
  }
  std::unique_ptr<TerminalViews> views;
  lessons::ReviewSession review(ctx.curriculum, ctx.progress, keys, *course, ctx.userId);
  while (true) {
    auto next = review.next();
    if (!next) return reportError("play: " + next.error().message);
    if (!*next) {
      terminalPrintf("\nNothing %sis due for review in this course now.\n", review.answered() ? "more " : "");
      break;
    }
    const quiz::ResolvedQuestion& resolved = (*next)->question;
    const lessons::QuestionScene& scene = (*next)->scene;
    const int number = review.answered() + 1;
    if (!views) views = openTerminalViews(ctx.session.database(), datasetId, ctx.viewsDir, ctx.noViews);
    std::vector<std::string> choiceNames;
    for (const std::string& id : resolved.choices) choiceNames.push_back(nameById.count(id) ? nameById[id] : id);
    const quiz::QuestionKind kind = resolved.question.kind;
    printQuestion("[review " + std::to_string(number) + "]", kind, resolved.question.prompt, choiceNames);
    showPicture(views.get(), scene, "review-" + std::to_string(number), kind == quiz::QuestionKind::Locate);
    std::fflush(stdout);

    AskedQuestion q{kind, resolved.question.target, resolved.choices, structureIdsByName(*structures), views.get(),
                    std::nullopt};
    auto result = askQuestion(ctx.source, q, [&](const quiz::Answer& answer, std::int64_t latencyMs)
                                                 -> Result<std::optional<quiz::Grade>> {
      auto grade = review.answer(answer, terminalRender(scene), latencyMs);
      if (!grade) return tl::unexpected(grade.error());
      notePracticePick(ctx, answer);
      return std::optional<quiz::Grade>(*grade);
    });
    if (!result) return reportError("play: " + result.error().message + " (earlier answers are saved)");
    if (*result != Asked::Answered) {  // a review has nothing to resume: stopping is fine
      terminalPrintf("\n%s\n", *result == Asked::Quit ? "stopped" : "no more answers");
      break;
    }
    sendClassEvents(ctx);
  }
  terminalPrintf("Review answers saved: %d, %d correct.\n", review.answered(), review.right());
  return 0;
}

int runLesson(const std::string& lessonId, lessons::LessonMode mode, PlayContext& ctx) {
  auto lesson = ctx.curriculum.lesson(lessonId);
  if (!lesson) return reportError("play: " + lesson.error().message + " (see `anatomy-tutor lessons`)");
  auto course = ctx.curriculum.course(lesson->courseId);
  if (!course) return reportError("play: " + course.error().message);
  auto structures = ctx.session.structures(course->datasetId);
  if (!structures) return reportError("play: " + structures.error().message);
  const std::string datasetId = course->datasetId;
  auto madeEngine = ctx.session.engineFor(lessonId);
  if (!madeEngine) return reportError("play: " + madeEngine.error().message);
  lessons::LessonEngine& engine = **madeEngine;
  if (auto started = engine.start(ctx.userId, lessonId, mode); !started)
    return reportError("play: " + started.error().message);

  terminalPrintf("Lesson: %s (%s), course %s — %s attempt %lld%s\n", rowCell(engine.lesson().title).c_str(), lessonId.c_str(),
              rowCell(course->title).c_str(), engine.resumed() ? "resuming" : "new", (long long)engine.attempt().id,
              engine.attempt().mode == lessons::LessonMode::QuizOnly ? ", quiz only" : "");
  if (!engine.lesson().summary.empty()) printWrapped(engine.lesson().summary, 2);
  std::fflush(stdout);
  auto views = openTerminalViews(ctx.session.database(), datasetId, ctx.viewsDir, ctx.noViews);

  const bool waitOnShow = ctx.source.interactive() && isatty(0);
  // After a step that asks nothing (a show step, a question answered before): at a terminal, Enter
  // goes on and 'back' to the previous step. False when the input ended.
  enum class Then { Next, Back, Stop };
  const auto waitAfterStep = [&]() -> Then {
    if (!waitOnShow) return Then::Next;
    terminalPrintf("  (Enter to continue, 'back' for the previous step) ");
    std::fflush(stdout);
    std::string line;
    if (!std::getline(std::cin, line)) return Then::Stop;
    return str::lower(str::trim(line)) == "back" ? Then::Back : Then::Next;
  };
  const auto stepBack = [&] {
    if (auto st = engine.back(); !st) terminalPrintf("  (%s)\n", st.error().message.c_str());
  };
  while (!engine.atEnd()) {
    auto view = engine.current();
    if (!view) return reportError("play: " + view.error().message);
    char stem[160];
    std::snprintf(stem, sizeof stem, "%s-%02d", lessonId.c_str(), view->position);
    if (view->kind == lessons::StepKind::Show || view->feedback) {  // a step that asks nothing
      if (view->kind == lessons::StepKind::Show) {
        const std::string heading = view->title.empty() ? view->structureName : view->title;
        terminalPrintf("\n[%d/%d] %s\n", view->position, view->count, heading.c_str());
        if (view->labelsVisible && !view->structureName.empty() && view->structureName != heading)
          terminalPrintf("  structure: %s\n", view->structureName.c_str());
        showPicture(views.get(), view->scene, stem, false);
        printWrapped(view->text, 2);
        std::fflush(stdout);
      } else {  // answered before (reached by 'back'): its answer stands
        printQuestion("[" + std::to_string(view->position) + "/" + std::to_string(view->count) + "]", view->questionKind,
                      view->prompt, view->choiceNames);
        showPicture(views.get(), view->scene, stem, false);
        terminalPrintf("  answered:\n");
        printGrade(*view->feedback);
      }
      const Then then = waitAfterStep();
      if (then == Then::Stop) {
        terminalPrintf("\nstopped; run the same command to resume\n");
        return 0;
      }
      if (then == Then::Back) {
        stepBack();
        continue;
      }
    } else {
      printQuestion("[" + std::to_string(view->position) + "/" + std::to_string(view->count) + "]", view->questionKind,
                    view->prompt, view->choiceNames);
      showPicture(views.get(), view->scene, stem, view->questionKind == quiz::QuestionKind::Locate);
      std::fflush(stdout);
      AskedQuestion q{view->questionKind, view->structure, view->choiceIds, structureIdsByName(*structures), views.get(),
                      std::nullopt};
      auto asked = askQuestion(ctx.source, q, [&](const quiz::Answer& answer, std::int64_t latencyMs)
                                                  -> Result<std::optional<quiz::Grade>> {
        auto grade = engine.answer(answer, terminalRender(view->scene), latencyMs);
        if (!grade) return tl::unexpected(grade.error());
        notePracticePick(ctx, answer);
        return std::optional<quiz::Grade>(*grade);
      }, false, true);
      if (asked && *asked == Asked::Back) {
        stepBack();
        continue;
      }
      if (!asked)
        return reportError("play: " + asked.error().message +
                           (asked.error().kind == ErrorKind::Io
                                ? " (earlier answers are saved; run the same command again to resume)"
                                : " (earlier answers are saved; fix the line and run again to resume)"));
      sendClassEvents(ctx);
      if (*asked == Asked::Answered) showAnswerIfWrong(engine, views.get(), view->questionId, stem);
      if (*asked != Asked::Answered) {
        terminalPrintf("\nstopped before step %d of %d; your answers are saved — run the same command to resume\n",
                    view->position, view->count);
        std::fflush(stdout);
        return *asked == Asked::Quit
                   ? 0
                   : reportError("play: " + std::string(ctx.source.interactive() ? "input" : "the answers file") +
                                 " ended before the lesson did (resume with the same command)");
      }
    }
    if (auto next = engine.next(); !next) return reportError("play: " + next.error().message);
  }

  auto score = engine.finish();
  if (!score) return reportError("play: " + score.error().message);
  int questions = 0, right = 0;
  for (const lessons::Step& step : engine.lesson().steps) questions += step.kind == lessons::StepKind::Question;
  auto responses = ctx.progress.responses(engine.attempt().id);
  if (responses)
    for (const auto& r : *responses) right += r.correct ? 1 : 0;
  terminalPrintf("\nLesson finished: %d of %s right (score %.2f).\n", right, str::countOf(questions, "question").c_str(),
              *score);
  printLessonReview(engine, views.get(), lessonId);
  return 0;
}

}  // namespace

int runPlay(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"answers", "group", "review", "views"}, {"quiz-only", "new-user", "no-views"});
  if (!args) return reportError("play: " + args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s", kPlayHelp);
    return 0;
  }
  const auto reviewCourse = args->value("review");
  if (reviewCourse) {
    if (!args->positional().empty()) return reportError("play: give either a LESSON or --review COURSE, not both");
    if (args->has("quiz-only")) return reportError("play: --quiz-only is for lessons, not --review");
  } else if (args->positional().size() != 1) {
    return reportError("play: give exactly one LESSON (see `anatomy-tutor lessons`)");
  }
  if (args->has("views") && args->has("no-views")) return reportError("play: give --views DIR or --no-views, not both");
  const auto userName = args->user();
  if (!userName) return reportError("play: --user NAME is required");

  auto source = answerSource(args->value("answers"));
  if (!source) return reportError("play: " + source.error().message);

  auto session = LearningSession::open(args->db());
  if (!session) return reportError("play: " + session.error().message);
  bool created = false;
  auto user = (*session)->user(*userName,
                               args->has("new-user") ? LearningSession::NewUser::Create : LearningSession::NewUser::Refuse,
                               args->valueOr("group", ""), &created);
  if (!user) return reportError("play: " + user.error().message);
  if (created) terminalPrintf("created user '%s'\n", user->name.c_str());

  OutboxSender classEvents((*session)->database());
  PlayContext ctx{**session, (*session)->curriculum(), (*session)->progress(), **source, user->id, args->value("views"),
                  args->has("no-views"), &classEvents, answersGoToClassServer((*session)->database(), user->name)};
  const auto mode = args->has("quiz-only") ? lessons::LessonMode::QuizOnly : lessons::LessonMode::Guided;
  const int status = reviewCourse ? runReview(*reviewCourse, ctx) : runLesson(args->positional()[0], mode, ctx);
  sendClassEvents(ctx, true);  // however it ended: what was saved goes to the class too
  return status;
}

}  // namespace at::app
