// anatomy-tutor play: one lesson in the terminal through the LessonEngine, or (--review COURSE)
// the course's review questions through lessons::answerReview. Answers come from a JSON-lines file
// (--answers) or interactively from stdin. Every answer is committed to the database before its
// feedback is printed, so an interrupted lesson resumes at the next step.
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <sstream>
#include <unistd.h>

#include "cli_args.h"
#include "core/strings.h"
#include "commands.h"
#include "learning_support.h"
#include "lessons/lesson_engine.h"
#include "quiz/answer_json.h"

namespace at::app {

namespace {

constexpr const char* kPlayHelp =
    "usage: anatomy-tutor play LESSON --user NAME [--answers FILE.jsonl] [--quiz-only]\n"
    "                          [--new-user [--group GROUP]] [--db PATH]\n"
    "       anatomy-tutor play --review COURSE --user NAME [--answers FILE.jsonl] [--db PATH]\n\n"
    "Runs a lesson in the terminal: prints each step, asks its questions and grades the answers.\n"
    "Every answer is saved before the next step is shown; running the same command again after an\n"
    "interruption resumes at the next step.\n\n"
    "With --review, asks the course's review questions instead (structures due for review, or never\n"
    "answered, chosen to suit the user's ability) until nothing is due or the answers end. Each\n"
    "answer is saved and reschedules its structure (`anatomy-tutor progress` shows the queue).\n\n"
    "  --answers    one JSON object per line answering the questions from the current one on:\n"
    "                 {\"choice\": 2}  index of a listed choice (they are printed numbered from 0)\n"
    "                 {\"text\": \"cochlea\"}  a typed name\n"
    "                 {\"pick\": \"stapes\", \"distance_mm\": 0.3}  the structure clicked (and, optionally,\n"
    "                 the weighted distance of the click from the target)\n"
    "                 {\"order\": [\"a\", \"b\"]}  structures in the order met\n"
    "               blank lines are skipped; a malformed line stops the run with its line number.\n"
    "               Without --answers the questions are asked on stdin (a number, a name, a list\n"
    "               separated by commas, or any of the JSON forms above; 'quit' stops and saves).\n"
    "  --quiz-only  questions only, without the teaching steps; labels and names hidden\n"
    "  --new-user   create the pseudonymous user NAME if it does not exist (with --group)\n"
    "  --db         database file (default: $XDG_DATA_HOME/anatomy-tutor/anatomy-tutor.db)\n";

// Prints `text` wrapped at ~96 columns with `indent` spaces in front of every line.
void printWrapped(const std::string& text, int indent) {
  std::istringstream words(text);
  std::string word, line;
  const std::string pad(std::size_t(indent), ' ');
  while (words >> word) {
    if (!line.empty() && line.size() + 1 + word.size() > std::size_t(96 - indent)) {
      std::printf("%s%s\n", pad.c_str(), line.c_str());
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) std::printf("%s%s\n", pad.c_str(), line.c_str());
}

// Where answers come from: a JSON-lines file (line numbers reported) or the terminal.
class AnswerSource {
 public:
  virtual ~AnswerSource() = default;
  // nullopt at the end of input.
  virtual std::optional<std::string> nextLine() = 0;
  virtual std::string where() const = 0;  // "answers.jsonl:7" or "stdin"
  virtual bool interactive() const = 0;
};

class FileAnswers final : public AnswerSource {
 public:
  explicit FileAnswers(std::string path) : path_(std::move(path)), in_(path_) {}
  bool ok() const { return bool(in_); }
  std::optional<std::string> nextLine() override {
    std::string line;
    while (std::getline(in_, line)) {
      ++lineNumber_;
      if (!str::trim(line).empty()) return line;
    }
    return std::nullopt;
  }
  std::string where() const override { return path_ + ":" + std::to_string(lineNumber_); }
  bool interactive() const override { return false; }

 private:
  std::string path_;
  std::ifstream in_;
  int lineNumber_ = 0;
};

class TerminalAnswers final : public AnswerSource {
 public:
  std::optional<std::string> nextLine() override {
    std::printf("  answer> ");
    std::fflush(stdout);
    std::string line;
    if (!std::getline(std::cin, line)) return std::nullopt;
    return line;
  }
  std::string where() const override { return "stdin"; }
  bool interactive() const override { return true; }
};

// A terminal reply to an answer: the JSON forms, or the plain forms per question kind.
Result<quiz::Answer> parseTerminalAnswer(const std::string& raw, const lessons::StepView& view,
                                         const std::map<std::string, std::string>& idByName) {
  const std::string text = str::trim(raw);
  if (!text.empty() && text[0] == '{') return quiz::answerFromJson(text);
  auto structureId = [&](const std::string& name) -> Result<std::string> {
    auto it = idByName.find(str::lower(str::trim(name)));
    if (it == idByName.end()) return fail("no structure called '" + str::trim(name) + "'");
    return it->second;
  };
  quiz::Answer answer;
  switch (view.questionKind) {
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation: {
      char* end = nullptr;
      const long n = std::strtol(text.c_str(), &end, 10);
      if (text.empty() || *end != '\0') return fail("type the number of a choice");
      answer.choice = int(n);
      break;
    }
    case quiz::QuestionKind::Name:
      answer.text = text;
      break;
    case quiz::QuestionKind::Locate: {
      auto id = structureId(text);
      if (!id) return tl::unexpected(id.error());
      answer.pick = quiz::Pick{*id, -1};
      break;
    }
    case quiz::QuestionKind::Order: {
      std::vector<std::string> order;
      std::stringstream parts(text);
      std::string part;
      while (std::getline(parts, part, ',')) {
        if (str::trim(part).empty()) continue;
        auto id = structureId(part);
        order.push_back(id ? *id : str::trim(part));
      }
      if (order.empty()) return fail("list the structures separated by commas");
      answer.order = std::move(order);
      break;
    }
  }
  return answer;
}

void printStep(const lessons::StepView& v) {
  if (v.kind == lessons::StepKind::Show) {
    const std::string heading = v.title.empty() ? v.structureName : v.title;
    std::printf("\n[%d/%d] %s\n", v.position, v.count, heading.c_str());
    if (v.labelsVisible && !v.structureName.empty() && v.structureName != heading)
      std::printf("  structure: %s\n", v.structureName.c_str());
    std::printf("  view: %s, preset %s\n", lessons::toString(v.view), v.presetId.c_str());
    printWrapped(v.text, 2);
  } else {
    std::printf("\n[%d/%d] Question (%s)\n", v.position, v.count, quiz::toString(v.questionKind));
    printWrapped(v.prompt, 2);
    for (std::size_t i = 0; i < v.choiceNames.size(); ++i)
      std::printf("    %zu) %s\n", i, v.choiceNames[i].c_str());
  }
  std::fflush(stdout);
}

enum class Asked { Graded, Quit, InputEnded };

// Reads answers to the question `view` until one is graded by `grade` (which records it), printing
// the grade. Interactive input may retry after a bad answer; from a file a bad answer is an error
// naming its line.
Result<Asked> askQuestion(AnswerSource& source, const lessons::StepView& view,
                          const std::map<std::string, std::string>& idByName,
                          const std::function<Result<quiz::Grade>(const quiz::Answer&, std::int64_t)>& grade) {
  const auto shownAt = std::chrono::steady_clock::now();
  while (true) {
    auto line = source.nextLine();
    if (!line) return Asked::InputEnded;
    if (source.interactive() && str::lower(str::trim(*line)) == "quit") return Asked::Quit;
    auto answer = source.interactive() ? parseTerminalAnswer(*line, view, idByName) : quiz::answerFromJson(*line);
    // Answers read from a file have no response time: 0 records "not measured" (never rated Easy).
    const auto latency = source.interactive() ? std::chrono::duration_cast<std::chrono::milliseconds>(
                                                    std::chrono::steady_clock::now() - shownAt)
                                              : std::chrono::milliseconds(0);
    Result<quiz::Grade> graded = answer ? grade(*answer, latency.count())
                                        : Result<quiz::Grade>(tl::unexpected(answer.error()));
    if (graded) {
      std::printf("  %s (score %.2f): ", graded->correct ? "correct" : "wrong", graded->score);
      printWrapped(graded->feedback, 0);
      std::fflush(stdout);
      return Asked::Graded;
    }
    std::fflush(stdout);
    // A bad answer names its line; a storage failure (a full disk) is not the line's fault.
    if (!source.interactive())
      return tl::unexpected(graded.error().kind == ErrorKind::Io ? graded.error()
                                                                 : withContext(source.where(), graded.error()));
    std::printf("  %s — try again\n", graded.error().message.c_str());
  }
}

// What `play` shows on a terminal: no 3-D view, so no preset and the default t, α, β.
lessons::RenderState terminalRender() {
  lessons::RenderState render;
  render.mode = "terminal";
  return render;
}

// play --review COURSE: review questions until nothing is due or the answers end.
int runReview(const std::string& courseId, std::int64_t userId, db::Database& database,
              db::SqliteCurriculumRepository& curriculum, db::SqliteProgressRepository& progress,
              AnswerSource& source) {
  auto course = curriculum.course(courseId);
  if (!course) return reportError("play: " + course.error().message + " (see `anatomy-tutor courses`)");
  auto structures = curriculum.structures(course->datasetId);
  if (!structures) return reportError("play: " + structures.error().message);
  std::map<std::string, std::string> idByName, nameById;
  for (const Structure& s : *structures) {
    idByName[str::lower(s.id)] = s.id;
    idByName[str::lower(s.displayName)] = s.id;
    nameById[s.id] = s.displayName.empty() ? s.id : s.displayName;
  }
  const std::string datasetId = course->datasetId;
  LazyKeyComputer keys(*structures, [&database, datasetId] { return loadCourseDataset(database, datasetId); });

  std::printf("Review: %s (%s)\n", course->title.c_str(), courseId.c_str());
  int asked = 0, right = 0;
  while (true) {
    const auto now = lessons::UnixSeconds(std::time(nullptr));
    auto question = lessons::chooseReviewQuestion(curriculum, progress, userId, courseId, now);
    if (!question) return reportError("play: " + question.error().message);
    if (!*question) {
      std::printf("\nNothing %sis due for review in this course now.\n", asked ? "more " : "");
      break;
    }
    auto resolved = quiz::resolveQuestion(**question, keys);
    if (!resolved) return reportError("play: " + resolved.error().message);
    lessons::StepView view;  // for the terminal answer forms
    view.kind = lessons::StepKind::Question;
    view.questionId = resolved->question.id;
    view.questionKind = resolved->question.kind;
    view.prompt = resolved->question.prompt;
    view.choiceIds = resolved->choices;
    for (const std::string& id : resolved->choices) view.choiceNames.push_back(nameById.count(id) ? nameById[id] : id);
    std::printf("\n[review %d] Question (%s)\n", asked + 1, quiz::toString(view.questionKind));
    printWrapped(view.prompt, 2);
    for (std::size_t i = 0; i < view.choiceNames.size(); ++i) std::printf("    %zu) %s\n", i, view.choiceNames[i].c_str());
    std::fflush(stdout);

    bool correct = false;
    auto result = askQuestion(source, view, idByName, [&](const quiz::Answer& answer, std::int64_t latencyMs) {
      lessons::ReviewAnswer review;
      review.userId = userId;
      review.courseId = courseId;
      review.question = resolved->question;
      review.answer = answer;
      review.render = terminalRender();
      review.latencyMs = latencyMs;
      auto grade = lessons::answerReview(curriculum, progress, keys, review);
      if (grade) correct = grade->correct;
      return grade;
    });
    if (!result) return reportError("play: " + result.error().message + " (earlier answers are saved)");
    if (*result != Asked::Graded) {  // a review has nothing to resume: stopping is fine
      std::printf("\n%s\n", *result == Asked::Quit ? "stopped" : "no more answers");
      break;
    }
    ++asked;
    right += correct ? 1 : 0;
  }
  std::printf("Review answers saved: %d, %d correct.\n", asked, right);
  return 0;
}

}  // namespace

int runPlay(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"user", "answers", "db", "group", "review"}, {"quiz-only", "new-user"});
  if (!args) return reportError("play: " + args.error().message);
  if (args->has("help")) {
    std::printf("%s", kPlayHelp);
    return 0;
  }
  const auto reviewCourse = args->value("review");
  if (reviewCourse) {
    if (!args->positional().empty()) return reportError("play: give either a LESSON or --review COURSE, not both");
    if (args->has("quiz-only")) return reportError("play: --quiz-only is for lessons, not --review");
  } else if (args->positional().size() != 1) {
    return reportError("play: give exactly one LESSON (see `anatomy-tutor lessons`)");
  }
  const std::string lessonId = reviewCourse ? "" : args->positional()[0];
  const auto userName = args->value("user");
  if (!userName || userName->empty()) return reportError("play: --user NAME is required");

  std::unique_ptr<AnswerSource> source;
  if (auto path = args->value("answers")) {
    auto file = std::make_unique<FileAnswers>(*path);
    if (!file->ok()) return reportError("play: --answers " + *path + ": cannot open");
    source = std::move(file);
  } else {
    source = std::make_unique<TerminalAnswers>();
  }

  auto database = openLearningDatabase(args->value("db"));
  if (!database) return reportError("play: " + database.error().message);
  db::SqliteCurriculumRepository curriculum(*database, builtinStructures());
  db::SqliteProgressRepository progress(*database);
  db::SqliteUserRepository users(*database);

  auto user = users.findUser(*userName);
  if (!user) return reportError("play: " + user.error().message);
  if (!*user) {
    if (!args->has("new-user"))
      return reportError("play: unknown user '" + *userName + "' (first time? add --new-user to create it)");
    auto created = users.createUser(*userName, lessons::Role::Student, args->valueOr("group", ""));
    if (!created) return reportError("play: " + created.error().message);
    std::printf("created user '%s'\n", created->name.c_str());
    *user = *created;
  }

  if (reviewCourse) return runReview(*reviewCourse, (*user)->id, *database, curriculum, progress, *source);

  auto lesson = curriculum.lesson(lessonId);
  if (!lesson) return reportError("play: " + lesson.error().message + " (see `anatomy-tutor lessons`)");
  auto course = curriculum.course(lesson->courseId);
  if (!course) return reportError("play: " + course.error().message);
  auto structures = curriculum.structures(course->datasetId);
  if (!structures) return reportError("play: " + structures.error().message);
  std::map<std::string, std::string> idByName;
  for (const Structure& s : *structures) {
    idByName[str::lower(s.id)] = s.id;
    idByName[str::lower(s.displayName)] = s.id;
  }

  db::Database& databaseRef = *database;
  const std::string datasetId = course->datasetId;
  LazyKeyComputer keys(*structures, [&databaseRef, datasetId] { return loadCourseDataset(databaseRef, datasetId); });

  lessons::LessonEngine engine(curriculum, progress, keys);
  const auto mode = args->has("quiz-only") ? lessons::LessonMode::QuizOnly : lessons::LessonMode::Guided;
  if (auto started = engine.start((*user)->id, lessonId, mode); !started)
    return reportError("play: " + started.error().message);

  std::printf("Lesson: %s (%s), course %s — %s attempt %lld%s\n", engine.lesson().title.c_str(), lessonId.c_str(),
              course->title.c_str(), engine.resumed() ? "resuming" : "new", (long long)engine.attempt().id,
              engine.attempt().mode == lessons::LessonMode::QuizOnly ? ", quiz only" : "");
  if (!engine.lesson().summary.empty()) printWrapped(engine.lesson().summary, 2);
  std::fflush(stdout);

  const bool waitOnShow = source->interactive() && isatty(0);
  while (!engine.atEnd()) {
    auto view = engine.current();
    if (!view) return reportError("play: " + view.error().message);
    printStep(*view);
    if (view->kind == lessons::StepKind::Question) {
      auto asked = askQuestion(*source, *view, idByName, [&](const quiz::Answer& answer, std::int64_t latencyMs) {
        return engine.answer(answer, terminalRender(), latencyMs);
      });
      if (!asked)
        return reportError("play: " + asked.error().message +
                           (asked.error().kind == ErrorKind::Io
                                ? " (earlier answers are saved; run the same command again to resume)"
                                : " (earlier answers are saved; fix the line and run again to resume)"));
      if (*asked != Asked::Graded) {
        std::printf("\nstopped before step %d of %d; your answers are saved — run the same command to resume\n",
                    view->position, view->count);
        std::fflush(stdout);
        return *asked == Asked::Quit ? 0
                                     : reportError("play: " + std::string(source->interactive() ? "input" : "the answers file") +
                                                   " ended before the lesson did (resume with the same command)");
      }
    } else if (waitOnShow) {
      std::printf("  (Enter to continue) ");
      std::fflush(stdout);
      std::string ignored;
      if (!std::getline(std::cin, ignored)) {
        std::printf("\nstopped; run the same command to resume\n");
        return 0;
      }
    }
    if (auto next = engine.next(); !next) return reportError("play: " + next.error().message);
  }

  auto score = engine.finish();
  if (!score) return reportError("play: " + score.error().message);
  auto ability = engine.ability();
  std::printf("\nLesson finished: score %.2f", *score);
  if (ability) std::printf(", ability %.0f", *ability);
  std::printf("\n");
  return 0;
}

}  // namespace at::app
