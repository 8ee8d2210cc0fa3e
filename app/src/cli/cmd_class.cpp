// anatomy-tutor class …: classes on a class server (create, join with a code, give roles, the
// instructor's view of the class's progress) and `anatomy-tutor sync`, which sends a learner's
// waiting class events (db/class_server.h).
#include <sys/stat.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>

#include "class_exam_cli.h"
#include "class_sync.h"
#include "cli_args.h"
#include "commands.h"
#include "core/strings.h"
#include "db/class_accounts.h"
#include "db/class_server.h"
#include "db/course_store.h"
#include "learning_session.h"
#include "quiz/study_report.h"
#include "printable_output.h"

namespace at::app {

namespace {

constexpr const char* kClassHelp =
    "usage: anatomy-tutor class create TITLE --db SERVER --user NAME\n"
    "       anatomy-tutor class join CODE --server SERVER --user NAME [--db PATH]\n"
    "       anatomy-tutor class role CODE MEMBER ROLE --db SERVER --user NAME\n"
    "       anatomy-tutor class progress CODE --db SERVER --user NAME [--csv]\n"
    "       anatomy-tutor class account CODE NAME --role ROLE --db SERVER [--pgpass FILE]\n"
    "       anatomy-tutor class withdraw CODE MEMBER --reason TEXT --db SERVER\n"
    "       anatomy-tutor class correct EVENT_ID --correct 0|1 --score S --reason TEXT --db SERVER\n"
    "       anatomy-tutor class audit CODE --db SERVER [--csv]\n"
    "       anatomy-tutor class open-exam CODE EXAM --db SERVER [--local-db PATH] [--views DIR]\n"
    "       anatomy-tutor class close-exam CODE EXAM --db SERVER\n"
    "       anatomy-tutor class keys CODE --db SERVER [--course ID] [--local-db PATH]\n\n"
    "A class lives on a class server, a PostgreSQL database every member's machine can reach\n"
    "(SERVER: postgresql://LOGIN@host/database, the password in ~/.pgpass; see the README).\n"
    "Each person has their own login (`class account`); on the server a login is who you are, and\n"
    "--user can only repeat it (the administrator's login names the member it acts for).\n"
    "  create    (the administrator) makes a class, prints its code and puts the installed courses\n"
    "            on the server with their answer keys (those whose dataset this machine has; the\n"
    "            others are named, for `class keys`; locate questions need `class keys` for their\n"
    "            pictures' pixels); NAME becomes its coordinator\n"
    "  join      joins NAME to the class with CODE as a student, on the server and in the local\n"
    "            database (--db, default: the usual one): from then on NAME's answers, lesson\n"
    "            starts and ends in `play` and the desktop are sent to the class. While the server\n"
    "            cannot be reached they wait in the local database's outbox and are sent when it\n"
    "            is back (or with `anatomy-tutor sync`); learning goes on meanwhile.\n"
    "  role      a coordinator (NAME) makes MEMBER a student, instructor or coordinator\n"
    "  progress  for instructors and coordinators: each student's graded answers, share right,\n"
    "            answers waiting for their keys, structures, lessons started and finished and\n"
    "            last activity, and each structure's graded answers, computed from the events the\n"
    "            server has (--csv: the students as CSV; answers and correct are the graded ones)\n"
    "  account   a coordinator makes NAME's login (ROLE: student, instructor or coordinator) and\n"
    "            prints its password once (--pgpass FILE: appends a ~/.pgpass line to FILE instead);\n"
    "            a login that exists keeps its password and gets the role in this class\n"
    "  withdraw  a coordinator excludes MEMBER, or a member withdraws (consent withdrawn); the\n"
    "            reason is kept and shown in `class progress`\n"
    "  correct   a coordinator corrects one answer's grade on the server\n"
    "  audit     role changes, accounts, withdrawals and corrections: who, when, old, new, why\n"
    "  open-exam an instructor or coordinator opens a graded exam: its items are drawn from the\n"
    "            course on this machine (--local-db), identify and name items sent as pictures, and\n"
    "            the keys kept on the server, where no student's login can read them. Students who\n"
    "            joined the class then take it with `anatomy-tutor exam EXAM --user NAME`: each\n"
    "            answer is graded on the server. `class progress` shows the scores\n"
    "  close-exam ends it: no new sittings; open ones are handed in with what they answered\n"
    "  keys      an instructor or coordinator publishes the answer keys of the courses (--course: one)\n"
    "            from this machine (--local-db) to the server, which then grades every lesson and\n"
    "            review answer itself; until then the class's answers wait there ungraded (`class\n"
    "            progress` shows them as waiting, apart from the graded ones). A locate answer\n"
    "            counts when picked on the question's picture in `play`; any other locate pick is\n"
    "            kept there as practice\n";

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
  // The server judges events against the course (its questions, lessons and prerequisites).
  auto seeded = db::seedCourses(*server, courseDirectory());
  if (!seeded) return reportError("class create: putting the courses on the server: " + seeded.error().message);
  terminalPrintf("class '%s': code %s (%s is its coordinator)\n", rowCell(made->title).c_str(), made->code.c_str(),
              args.user()->c_str());
  // Their answer keys go with them, so that the server grades answers from the first one on: each
  // course whose dataset this machine has (--local-db); the others are named with what to run.
  auto learning = LearningSession::open(args.value("local-db"));
  if (!learning) return reportError("class create: the answer keys: " + learning.error().message);
  std::vector<lessons::Course> courses;
  for (const db::SeedReport& r : *seeded) {
    auto course = (*learning)->curriculum().course(r.courseId);
    if (course) courses.push_back(std::move(*course));
    else terminalPrintf("course %s: its answer keys were not published (%s)\n", r.courseId.c_str(), course.error().message.c_str());
  }
  auto published = publishClassKeys(*server, made->code, **learning, courses, args.user(), false, false);
  if (!published) return reportError("class create: publishing the answer keys: " + published.error().message);
  std::string shown = db::withoutPassword(*args.db());  // the password is not printed
  if (shown != *args.db()) shown.insert(shown.find('@'), ":PASSWORD");
  terminalPrintf("make each person's login with: anatomy-tutor class account %s NAME --role student --db '%s'\n",
              made->code.c_str(), shown.c_str());
  return 0;
}

int runJoin(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("class join: give the class CODE");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class join: " + code.error().message);
  const auto url = args.value("server");
  if (!url) return reportError("class join: --server SERVER (the class server's postgresql:// URL) is required");
  auto server = openServer(*url);
  if (!server) return reportError("class join: " + server.error().message);
  auto name = db::actingName(*server, args.user());
  if (!name) return reportError("class join: " + name.error().message);
  auto info = db::findClass(*server, *code);
  if (!info) return reportError("class join: " + info.error().message);
  auto role = db::joinClass(*server, *code, *name);
  if (!role) return reportError("class join: " + role.error().message);
  auto local = db::openDatabase(args.db());
  if (!local) return reportError("class join: " + local.error().message);
  if (auto kept = db::rememberMembership(*local, {*name, *code, *url, *role}); !kept)
    return reportError("class join: " + kept.error().message);
  terminalPrintf("%s joined class %s (%s) as %s; answers in %s are sent to %s\n", name->c_str(), code->c_str(),
              rowCell(info->title).c_str(), db::toString(*role), local->path().c_str(), server->path().c_str());
  return 0;
}

int runRole(const cli::Args& args) {
  if (args.positional().size() != 4) return reportError("class role: give CODE MEMBER ROLE");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class role: " + code.error().message);
  auto role = db::parseClassRole(args.positional()[3]);
  if (!role) return reportError("class role: " + role.error().message);
  if (!args.db()) return reportError("class role: --db SERVER (the class server) is required");
  auto server = openServer(*args.db());
  if (!server) return reportError("class role: " + server.error().message);
  auto by = db::actingName(*server, args.user());
  if (!by) return reportError("class role: " + by.error().message);
  if (auto set = db::setMemberRole(*server, *code, *by, args.positional()[2], *role); !set)
    return reportError("class role: " + set.error().message);
  terminalPrintf("%s is %s of class %s\n", args.positional()[2].c_str(), db::toString(*role), code->c_str());
  return 0;
}

// The mean score of the graded exams a student handed in (as a percentage, or as a share for
// CSV); "" when none was handed in.
std::string examScore(const db::StudentClassProgress& s, bool percent) {
  if (!s.examScore) return "";
  char text[32];
  if (percent) std::snprintf(text, sizeof text, "%.0f%%", 100 * *s.examScore);
  else std::snprintf(text, sizeof text, "%.3f", *s.examScore);
  return text;
}

int runClassProgress(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("class progress: give the class CODE");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class progress: " + code.error().message);
  if (!args.db()) return reportError("class progress: --db SERVER (the class server) is required");
  auto server = openServer(*args.db());
  if (!server) return reportError("class progress: " + server.error().message);
  auto progress = db::classProgress(*server, *code, args.user().value_or(""));
  if (!progress) return reportError("class progress: " + progress.error().message);
  if (args.has("csv")) {
    terminalPrintf("student,answers,correct,structures,lessons_started,lessons_finished,last_active_unix,withdrawn,"
                   "exams_handed_in,exam_score,ungraded,practice\n");
    for (const auto& s : progress->students)
      terminalPrintf("%s,%d,%d,%d,%d,%d,%s,%s,%d,%s,%d,%d\n", quiz::csvQuoted(s.userName).c_str(), s.answers, s.correct,
                     s.structures, s.lessonsStarted, s.lessonsFinished,
                     s.lastActive ? std::to_string(*s.lastActive).c_str() : "",
                     quiz::csvQuoted(s.withdrawal.value_or("")).c_str(), s.examsHandedIn, examScore(s, false).c_str(),
                     s.ungraded, s.practice);
    return 0;
  }
  terminalPrintf("Class %s — %s: %s, %s received\n\n", rowCell(progress->info.code).c_str(), rowCell(progress->info.title).c_str(),
              str::countOf(long(progress->students.size()), "student").c_str(),
              str::countOf(long(progress->events), "event").c_str());
  // "answers" and "right" are the graded answers; "waiting" those whose keys are not published yet.
  terminalPrintf("%-20s %8s %6s %8s %11s %8s %9s %11s  %s\n", "student", "answers", "right", "waiting", "structures",
                 "lessons", "finished", "exam score", "last active");
  for (const auto& s : progress->students)
    terminalPrintf("%-20s %8d %6s %8d %11d %8d %9d %11s  %s%s\n", rowCell(s.userName).c_str(), s.answers,
                   share(s.correct, s.answers).c_str(), s.ungraded, s.structures, s.lessonsStarted, s.lessonsFinished,
                   examScore(s, true).c_str(), when(s.lastActive).c_str(),
                s.withdrawal ? ("  (withdrawn: " + rowCell(*s.withdrawal) + ")").c_str() : "");
  int ungraded = 0, practice = 0;
  for (const auto& s : progress->students) {
    ungraded += s.ungraded;
    practice += s.practice;
  }
  if (ungraded > 0)
    terminalPrintf("\n%s waiting, not counted yet: their answer keys are not on the server; publish them from an "
                   "instructor's machine with: anatomy-tutor class keys %s --db SERVER\n",
                   str::countOf(ungraded, "answer").c_str(), progress->info.code.c_str());
  if (practice > 0)
    terminalPrintf("%s kept as practice and not counted: locate picks the server cannot grade (made outside the "
                   "question's picture in `play`)\n",
                   str::countOf(practice, "answer").c_str());
  if (!progress->structures.empty()) {
    terminalPrintf("\n%-24s %9s %8s %6s\n", "structure", "students", "answers", "right");
    for (const auto& s : progress->structures)
      terminalPrintf("%-24s %9d %8d %6s\n", rowCell(s.structureId).c_str(), s.students, s.answers, share(s.correct, s.answers).c_str());
  }
  return 0;
}

// The parts of a postgresql:// URL a ~/.pgpass line needs; nullopt when it has no host or database.
struct ServerAddress {
  std::string host, port = "5432", database;
};
std::optional<ServerAddress> addressOf(const std::string& url) {
  std::string rest = url.substr(url.find("://") + 3);
  if (auto query = rest.find('?'); query != std::string::npos) rest.erase(query);
  if (auto at = rest.rfind('@'); at != std::string::npos) rest.erase(0, at + 1);
  const auto slash = rest.find('/');
  if (slash == std::string::npos || slash + 1 >= rest.size()) return std::nullopt;
  ServerAddress a;
  a.database = rest.substr(slash + 1);
  std::string hostPort = rest.substr(0, slash);
  if (auto colon = hostPort.rfind(':'); colon != std::string::npos && hostPort.find(']') == std::string::npos) {
    a.port = hostPort.substr(colon + 1);
    hostPort.erase(colon);
  }
  a.host = hostPort.empty() ? "localhost" : hostPort;
  return a;
}

// A ~/.pgpass field: colons and backslashes escaped with a backslash.
std::string pgpassField(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == ':' || c == '\\') out += '\\';
    out += c;
  }
  return out;
}

int runAccount(const cli::Args& args) {
  if (args.positional().size() != 3) return reportError("class account: give CODE NAME");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class account: " + code.error().message);
  const auto roleText = args.value("role");
  if (!roleText) return reportError("class account: --role student|instructor|coordinator is required");
  auto role = db::parseClassRole(*roleText);
  if (!role) return reportError("class account: " + role.error().message);
  if (!args.db()) return reportError("class account: --db SERVER (the class server) is required");
  auto server = openServer(*args.db());
  if (!server) return reportError("class account: " + server.error().message);
  const std::string& name = args.positional()[2];
  auto account = db::createClassAccount(*server, *code, name, *role, args.user());
  if (!account) return reportError("class account: " + account.error().message);
  const auto address = addressOf(*args.db());
  terminalPrintf("%s is %s of class %s\n", name.c_str(), db::toString(*role), code->c_str());
  if (!account->password) {
    terminalPrintf("the login %s existed already and keeps its password\n", name.c_str());
    return 0;
  }
  if (const auto pgpass = args.value("pgpass")) {
    if (!address) return reportError("class account: --pgpass needs a SERVER URL with host and database");
    const bool existed = std::ifstream(*pgpass).good();
    std::ofstream out(*pgpass, std::ios::app);
    if (!out) return reportError("class account: cannot write " + *pgpass + " (the login was made: run it again after "
                                 "fixing the file, or reset the password on the server)");
    out << pgpassField(address->host) << ':' << address->port << ':' << pgpassField(address->database) << ':'
        << pgpassField(name) << ':' << pgpassField(*account->password) << '\n';
    out.close();
    if (!existed) ::chmod(pgpass->c_str(), 0600);
    terminalPrintf("its password is in %s (a ~/.pgpass line for %s, mode 600)\n", pgpass->c_str(), name.c_str());
  } else {
    terminalPrintf("password (shown once, not stored; hand it to %s): %s\n", name.c_str(), account->password->c_str());
  }
  if (address)
    terminalPrintf("%s connects as: postgresql://%s@%s:%s/%s (the password in ~/.pgpass: %s:%s:%s:%s:PASSWORD)\n",
                name.c_str(), name.c_str(), address->host.c_str(), address->port.c_str(), address->database.c_str(),
                address->host.c_str(), address->port.c_str(), address->database.c_str(), name.c_str());
  return 0;
}

int runWithdraw(const cli::Args& args) {
  if (args.positional().size() != 3) return reportError("class withdraw: give CODE MEMBER");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class withdraw: " + code.error().message);
  const auto reason = args.value("reason");
  if (!reason || reason->empty()) return reportError("class withdraw: --reason TEXT is required (it is kept)");
  if (!args.db()) return reportError("class withdraw: --db SERVER (the class server) is required");
  auto server = openServer(*args.db());
  if (!server) return reportError("class withdraw: " + server.error().message);
  auto by = db::actingName(*server, args.user());
  if (!by) return reportError("class withdraw: " + by.error().message);
  if (auto done = db::withdrawMember(*server, *code, args.positional()[2], *reason, *by); !done)
    return reportError("class withdraw: " + done.error().message);
  terminalPrintf("%s withdrawn from class %s (%s)\n", args.positional()[2].c_str(), code->c_str(), reason->c_str());
  return 0;
}

int runCorrect(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("class correct: give the EVENT_ID");
  const auto correct = args.value("correct"), score = args.value("score"), reason = args.value("reason");
  if (!correct || (*correct != "0" && *correct != "1")) return reportError("class correct: --correct 0|1 is required");
  if (!reason || reason->empty()) return reportError("class correct: --reason TEXT is required (it is kept)");
  double scoreValue = *correct == "1" ? 1.0 : 0.0;
  if (score) {
    char* end = nullptr;
    scoreValue = std::strtod(score->c_str(), &end);
    if (end == score->c_str() || *end || !(scoreValue >= 0 && scoreValue <= 1))
      return reportError("class correct: --score '" + *score + "' is not a number from 0 to 1");
  }
  if (!args.db()) return reportError("class correct: --db SERVER (the class server) is required");
  auto server = openServer(*args.db());
  if (!server) return reportError("class correct: " + server.error().message);
  auto by = db::actingName(*server, args.user());
  if (!by) return reportError("class correct: " + by.error().message);
  if (auto done = db::correctClassEvent(*server, args.positional()[1], *correct == "1", scoreValue, *reason, *by); !done)
    return reportError("class correct: " + done.error().message);
  terminalPrintf("event %s corrected (kept in the class audit)\n", args.positional()[1].c_str());
  return 0;
}

int runAudit(const cli::Args& args) {
  if (args.positional().size() != 2) return reportError("class audit: give the class CODE");
  auto code = db::normalizeClassCode(args.positional()[1]);
  if (!code) return reportError("class audit: " + code.error().message);
  if (!args.db()) return reportError("class audit: --db SERVER (the class server) is required");
  auto server = openServer(*args.db());
  if (!server) return reportError("class audit: " + server.error().message);
  auto entries = db::classAudit(*server, *code);
  if (!entries) return reportError("class audit: " + entries.error().message);
  terminalPrintf("recorded_at,actor,login,action,target,old,new,reason\n");
  for (const auto& e : *entries)
    terminalPrintf("%s,%s,%s,%s,%s,%s,%s,%s\n", e.recordedAt.c_str(), quiz::csvQuoted(e.actor).c_str(),
                quiz::csvQuoted(e.login).c_str(), e.action.c_str(), quiz::csvQuoted(e.target).c_str(),
                quiz::csvQuoted(e.oldValue.value_or("")).c_str(), quiz::csvQuoted(e.newValue.value_or("")).c_str(),
                quiz::csvQuoted(e.reason).c_str());
  return 0;
}

}  // namespace

int runClass(const Argv& argv) {
  auto args = cli::Args::parse(argv, {"server", "role", "pgpass", "reason", "correct", "score", "local-db", "views", "course"},
                               {"csv"});
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
  if (action == "account") return runAccount(*args);
  if (action == "withdraw") return runWithdraw(*args);
  if (action == "correct") return runCorrect(*args);
  if (action == "audit") return runAudit(*args);
  if (action == "open-exam") return runClassOpenExam(*args);
  if (action == "close-exam") return runClassCloseExam(*args);
  if (action == "keys") return runClassKeys(*args);
  return reportError("class: unknown action '" + action +
                         "' (create, join, role, progress, account, withdraw, correct, audit, open-exam, close-exam, keys)",
                     2);
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
  const bool refused = std::any_of(report->servers.begin(), report->servers.end(),
                                   [](const db::ServerSync& s) { return s.refused > 0; });
  if (refused) return reportError("sync: " + describeSync(*report));  // the server's reasons, status 1
  terminalPrintf("%s\n", describeSync(*report).c_str());
  return 0;
}

}  // namespace at::app
