// anatomy-tutor class …: classes on a class server (create, join with a code, give roles, the
// instructor's view of the class's progress) and `anatomy-tutor sync`, which sends a learner's
// waiting class events (db/class_server.h).
#include <cstdio>
#include <ctime>

#include "class_sync.h"
#include "cli_args.h"
#include "commands.h"
#include "core/strings.h"
#include "db/class_server.h"
#include "quiz/study_report.h"
#include "printable_output.h"

namespace at::app {

namespace {

constexpr const char* kClassHelp =
    "usage: anatomy-tutor class create TITLE --db SERVER --user NAME\n"
    "       anatomy-tutor class join CODE --server SERVER --user NAME [--db PATH]\n"
    "       anatomy-tutor class role CODE MEMBER ROLE --db SERVER --user NAME\n"
    "       anatomy-tutor class progress CODE --db SERVER --user NAME [--csv]\n\n"
    "A class lives on a class server, a PostgreSQL database every member's machine can reach\n"
    "(SERVER: postgresql://user:password@host/database; see the README).\n"
    "  create    makes a class and prints its code; NAME becomes its coordinator\n"
    "  join      joins NAME to the class with CODE as a student, on the server and in the local\n"
    "            database (--db, default: the usual one): from then on NAME's answers, lesson\n"
    "            starts and ends in `play` and the desktop are sent to the class. While the server\n"
    "            cannot be reached they wait in the local database's outbox and are sent when it\n"
    "            is back (or with `anatomy-tutor sync`); learning goes on meanwhile.\n"
    "  role      a coordinator (NAME) makes MEMBER a student, instructor or coordinator\n"
    "  progress  for instructors and coordinators: each student's answers, share right,\n"
    "            structures, lessons started and finished and last activity, and each structure's\n"
    "            answers, computed from the events the server has (--csv: the students as CSV)\n";

constexpr const char* kSyncHelp =
    "usage: anatomy-tutor sync [--db PATH]\n\n"
    "Sends the class events waiting in the local database's outbox (answers, lesson starts and\n"
    "ends of users who joined a class) to their class servers. Sending twice sends nothing twice:\n"
    "the server keeps each event once. Exit status 0 when nothing is left waiting, 1 otherwise\n"
    "(the line says why: e.g. the server cannot be reached; the events stay and wait).\n";

Result<db::Connection> openServer(const std::string& url) {
  if (!db::isPostgresUrl(url)) return fail("'" + url + "' is not a class server (postgresql://user:password@host/database)");
  db::OpenOptions options;
  options.create = false;
  return db::openDatabase(url, options);
}

std::string when(std::optional<std::int64_t> seconds) {
  if (!seconds) return "never";
  char text[32];
  const std::time_t t = std::time_t(*seconds);
  std::tm utc{};
  gmtime_r(&t, &utc);
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M UTC", &utc);
  return text;
}

std::string share(int part, int whole) {
  if (whole == 0) return "-";
  char text[16];
  std::snprintf(text, sizeof text, "%.0f%%", 100.0 * part / whole);
  return text;
}

int runCreate(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("class create: give the class's TITLE (one argument; quote it)");
  if (!args.db()) return reportError("class create: --db SERVER (the class server) is required");
  if (!args.user()) return reportError("class create: --user NAME (who coordinates the class) is required");
  auto server = openServer(*args.db());
  if (!server) return reportError("class create: " + server.error().message);
  auto made = db::createClass(*server, args.positional()[1], *args.user());
  if (!made) return reportError("class create: " + made.error().message);
  terminalPrintf("class '%s': code %s (%s is its coordinator)\n", made->title.c_str(), made->code.c_str(),
              args.user()->c_str());
  std::string shown = db::withoutPassword(*args.db());  // the password is not printed
  if (shown != *args.db()) shown.insert(shown.find('@'), ":PASSWORD");
  terminalPrintf("students join with: anatomy-tutor class join %s --server '%s' --user NAME\n", made->code.c_str(),
              shown.c_str());
  return 0;
}

int runJoin(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("class join: give the class CODE");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class join: " + code.error().message);
  const auto url = args.value("server");
  if (!url) return reportError("class join: --server SERVER (the class server's postgresql:// URL) is required");
  if (!args.user()) return reportError("class join: --user NAME is required");
  auto server = openServer(*url);
  if (!server) return reportError("class join: " + server.error().message);
  auto info = db::findClass(*server, *code);
  if (!info) return reportError("class join: " + info.error().message);
  auto role = db::joinClass(*server, *code, *args.user());
  if (!role) return reportError("class join: " + role.error().message);
  auto local = db::openDatabase(args.db());
  if (!local) return reportError("class join: " + local.error().message);
  if (auto kept = db::rememberMembership(*local, {*args.user(), *code, *url, *role}); !kept)
    return reportError("class join: " + kept.error().message);
  terminalPrintf("%s joined class %s (%s) as %s; answers in %s are sent to %s\n", args.user()->c_str(), code->c_str(),
              info->title.c_str(), db::toString(*role), local->path().c_str(), server->path().c_str());
  return 0;
}

int runRole(const cli::Args& args) {
  if (args.positional().size() != 4) return reportError("class role: give CODE MEMBER ROLE");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class role: " + code.error().message);
  auto role = db::parseClassRole(args.positional()[3]);
  if (!role) return reportError("class role: " + role.error().message);
  if (!args.db()) return reportError("class role: --db SERVER (the class server) is required");
  if (!args.user()) return reportError("class role: --user NAME (a coordinator of the class) is required");
  auto server = openServer(*args.db());
  if (!server) return reportError("class role: " + server.error().message);
  if (auto set = db::setMemberRole(*server, *code, *args.user(), args.positional()[2], *role); !set)
    return reportError("class role: " + set.error().message);
  terminalPrintf("%s is %s of class %s\n", args.positional()[2].c_str(), db::toString(*role), code->c_str());
  return 0;
}

int runClassProgress(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("class progress: give the class CODE");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class progress: " + code.error().message);
  if (!args.db()) return reportError("class progress: --db SERVER (the class server) is required");
  if (!args.user()) return reportError("class progress: --user NAME (an instructor of the class) is required");
  auto server = openServer(*args.db());
  if (!server) return reportError("class progress: " + server.error().message);
  auto progress = db::classProgress(*server, *code, *args.user());
  if (!progress) return reportError("class progress: " + progress.error().message);
  if (args.has("csv")) {
    terminalPrintf("student,answers,correct,structures,lessons_started,lessons_finished,last_active_unix\n");
    for (const auto& s : progress->students)
      terminalPrintf("%s,%d,%d,%d,%d,%d,%s\n", quiz::csvQuoted(s.userName).c_str(), s.answers, s.correct, s.structures,
                  s.lessonsStarted, s.lessonsFinished, s.lastActive ? std::to_string(*s.lastActive).c_str() : "");
    return 0;
  }
  terminalPrintf("Class %s — %s: %s, %s received\n\n", progress->info.code.c_str(), progress->info.title.c_str(),
              str::countOf(long(progress->students.size()), "student").c_str(),
              str::countOf(long(progress->events), "event").c_str());
  terminalPrintf("%-20s %8s %6s %11s %8s %9s  %s\n", "student", "answers", "right", "structures", "lessons", "finished",
              "last active");
  for (const auto& s : progress->students)
    terminalPrintf("%-20s %8d %6s %11d %8d %9d  %s\n", s.userName.c_str(), s.answers, share(s.correct, s.answers).c_str(),
                s.structures, s.lessonsStarted, s.lessonsFinished, when(s.lastActive).c_str());
  if (!progress->structures.empty()) {
    terminalPrintf("\n%-24s %9s %8s %6s\n", "structure", "students", "answers", "right");
    for (const auto& s : progress->structures)
      terminalPrintf("%-24s %9d %8d %6s\n", s.structureId.c_str(), s.students, s.answers, share(s.correct, s.answers).c_str());
  }
  return 0;
}

}  // namespace

int runClass(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"server"}, {"csv"});
  if (!args) return reportError("class: " + args.error().message);
  if (args->has("help") || args->positional().empty()) {
    terminalPrintf("%s", kClassHelp);
    return args->has("help") ? 0 : 2;
  }
  const std::string& action = args->positional()[0];
  if (action == "create") return runCreate(*args);
  if (action == "join") return runJoin(*args);
  if (action == "role") return runRole(*args);
  if (action == "progress") return runClassProgress(*args);
  return reportError("class: unknown action '" + action + "' (create, join, role, progress)", 2);
}

int runSync(const Argv& argv) {
  auto args = cli::Args::parse(argv, {}, {});
  if (!args) return reportError("sync: " + args.error().message);
  if (args->has("help")) {
    terminalPrintf("%s", kSyncHelp);
    return 0;
  }
  if (!args->positional().empty()) return reportError("sync: unexpected argument '" + args->positional()[0] + "'");
  auto local = db::openDatabase(args->db());
  if (!local) return reportError("sync: " + local.error().message);
  auto report = db::syncOutbox(*local);
  if (!report) return reportError("sync: " + report.error().message);
  if (!report->complete()) return reportError("sync: " + describeSync(*report));
  terminalPrintf("%s\n", describeSync(*report).c_str());
  return 0;
}

}  // namespace at::app
