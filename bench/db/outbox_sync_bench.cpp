// outbox_sync_bench: a class of students on their own machines sending their answers to a class
// server through the outbox (db/class_server.h), with the server stopped and started again in the
// middle. Each student has a SQLite file of their own; every answer is recorded as `play --review`
// records it (SqlProgressRepository::recordReviewAnswer: the answer, the learner model and the
// outbox event in one local transaction) and is followed by a sync, as `play` does. `--workers`
// threads play the students round-robin, each thread with one server connection (a sync after a
// failure opens a new one). When half the answers are recorded, --stop-command runs, the server
// stays down --down-seconds (answers go on, syncs fail and the events wait), --start-command runs.
// At the end every outbox is synced until empty and the server's events are checked against the
// students' own records: lost = answered but not on the server; duplicated = on the server more
// than once per answer. One JSON line.
//
//   outbox_sync_bench --server URL --dir DIR [--students 200] [--answers 50] [--workers 16]
//                     [--stop-command CMD --start-command CMD] [--down-seconds 3]
//
// bench/outbox_sync_bench.sh runs it against a throwaway PostgreSQL server (default durability).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "db/class_server.h"
#include "db/connection.h"
#include "db/course_store.h"
#include "db/sql_repositories.h"
#include "lessons/scheduling.h"

namespace {

using namespace at;
using Clock = std::chrono::steady_clock;

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, std::size_t(q * double(values.size() - 1) + 0.5))];
}

struct Options {
  std::string server, dir, stopCommand, startCommand;
  int students = 200, answers = 50, workers = 16, downSeconds = 3;
};

[[noreturn]] void die(const std::string& message) {
  std::fprintf(stderr, "outbox_sync_bench: %s\n", message.c_str());
  std::exit(2);
}

template <class T>
T ok(Result<T> r, const std::string& what) {
  if (!r) die(what + ": " + r.error().message);
  return std::move(*r);
}
void ok(const Status& s, const std::string& what) {
  if (!s) die(what + ": " + s.error().message);
}

struct Student {
  std::string name;
  db::Connection local;
  std::int64_t userId = 0;
  lessons::StructureProgress progress;
};

constexpr int kQuestions = 13;  // the bench course's questions, answered round-robin

std::string questionId(int n) { return "bench.q" + std::to_string(n % kQuestions); }
std::string structureId(int n) { return "structure_" + std::to_string(n % kQuestions); }

// The course the answers belong to: the class server judges every event against the courses it
// holds (a review answer counts only for a question it has, in a lesson open to the student), so
// the bench puts it there first. One lesson without prerequisites, one name question per structure.
lessons::Course benchCourse() {
  lessons::Course c;
  c.id = "outbox_sync_bench";
  c.title = "Outbox sync bench";
  c.datasetId = "outbox_sync_bench";
  lessons::Lesson lesson;
  lesson.id = "outbox_sync_bench.names";
  lesson.courseId = c.id;
  lesson.title = "Names";
  for (int n = 0; n < kQuestions; ++n) {
    lessons::Step step;
    step.kind = lessons::StepKind::Question;
    step.question.id = questionId(n);
    step.question.kind = quiz::QuestionKind::Name;
    step.question.prompt = "Name the highlighted structure.";
    step.question.target = structureId(n);
    lesson.steps.push_back(step);
  }
  c.lessons.push_back(lesson);
  return c;
}

// One review answer as play --review records it: the graded answer and its learner update.
lessons::ReviewRecord answerOf(Student& s, int n) {
  const auto now = lessons::UnixSeconds(1'790'000'000 + n * 60);
  const bool right = (n * 7 + int(s.userId)) % 3 != 0;
  lessons::ReviewRecord r;
  r.response.userId = s.userId;
  r.response.questionId = questionId(n);
  r.response.structureId = structureId(n);
  r.response.answer.text = right ? r.response.structureId : "other";
  r.response.correct = right;
  r.response.score = right ? 1 : 0;
  r.response.latencyMs = 1500 + n;
  r.response.answeredAt = now;
  const auto rating = right ? lessons::Rating::Good : lessons::Rating::Again;
  lessons::StructureProgress before{s.userId, r.response.structureId};
  r.update.progress = lessons::scheduleAnswer(before, rating, right, now, lessons::Fsrs());
  r.update.rating = rating;
  return r;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) die(a + " needs a value");
      return argv[++i];
    };
    if (a == "--server") o.server = next();
    else if (a == "--dir") o.dir = next();
    else if (a == "--students") o.students = std::stoi(next());
    else if (a == "--answers") o.answers = std::stoi(next());
    else if (a == "--workers") o.workers = std::stoi(next());
    else if (a == "--stop-command") o.stopCommand = next();
    else if (a == "--start-command") o.startCommand = next();
    else if (a == "--down-seconds") o.downSeconds = std::stoi(next());
    else die("unknown option " + a);
  }
  if (o.server.empty() || o.dir.empty()) die("--server URL and --dir DIR are required");
  if (o.students < 1 || o.answers < 1 || o.workers < 1) die("--students, --answers and --workers must be positive");

  // The course, the class, and every student joined on the server and on their own machine.
  db::OpenOptions serverOptions;
  serverOptions.create = false;
  auto server = ok(db::openDatabase(o.server, serverOptions), "opening the server");
  ok(db::storeCourse(server.get(), benchCourse(), "outbox_sync_bench"), "putting the bench course on the server");
  const std::string code = ok(db::createClass(server, "outbox sync bench", "coordinator"), "creating the class").code;
  std::vector<Student> students;
  students.reserve(std::size_t(o.students));
  for (int i = 0; i < o.students; ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "student%03d", i);
    const std::string path = (std::filesystem::path(o.dir) / (std::string(name) + ".db")).string();
    auto local = ok(db::openDatabase(path), path);
    ok(db::joinClass(server, code, name), "joining");
    ok(db::rememberMembership(local, {name, code, o.server, db::ClassRole::Student}), "remembering the class");
    db::SqlUserRepository users(local);
    const std::int64_t id = ok(users.createUser(name, lessons::Role::Student, ""), "creating a user").id;
    students.push_back(Student{name, std::move(local), id, {}});
  }

  const int total = o.students * o.answers;
  std::atomic<int> recorded{0}, failedSyncs{0};
  std::atomic<bool> down{false};
  std::mutex merge;
  std::vector<double> commitMs;
  std::string restartNote = "no restart";
  double downFor = 0;

  std::thread restarter;
  if (!o.stopCommand.empty()) {
    restarter = std::thread([&] {
      while (recorded.load() < total / 2) std::this_thread::sleep_for(std::chrono::milliseconds(5));
      const auto stopAt = Clock::now();
      if (std::system(o.stopCommand.c_str()) != 0) die("the stop command failed: " + o.stopCommand);
      down = true;
      std::this_thread::sleep_for(std::chrono::seconds(o.downSeconds));
      if (std::system(o.startCommand.c_str()) != 0) die("the start command failed: " + o.startCommand);
      down = false;
      downFor = std::chrono::duration<double>(Clock::now() - stopAt).count();
      restartNote = "stopped after " + std::to_string(total / 2) + " answers";
    });
  }

  const auto start = Clock::now();
  std::vector<std::thread> workers;
  for (int w = 0; w < o.workers; ++w) {
    workers.emplace_back([&, w] {
      db::ServerConnections connections;
      std::vector<double> mine;
      for (int n = 0; n < o.answers; ++n) {
        for (int s = w; s < o.students; s += o.workers) {
          Student& student = students[std::size_t(s)];
          db::SqlProgressRepository progress(student.local);
          ok(progress.recordReviewAnswer(answerOf(student, n)), student.name + ": recording");
          ++recorded;
          auto report = ok(db::syncOutbox(student.local, {}, &connections), student.name + ": sync");
          if (!report.complete()) ++failedSyncs;
          mine.insert(mine.end(), report.commitMs.begin(), report.commitMs.end());
        }
      }
      std::lock_guard lock(merge);
      commitMs.insert(commitMs.end(), mine.begin(), mine.end());
    });
  }
  for (auto& t : workers) t.join();
  if (restarter.joinable()) restarter.join();
  // Whatever still waits (events of the last answers before the restart finished) goes now.
  db::ServerConnections last;
  for (Student& s : students) {
    for (int tries = 0;; ++tries) {
      auto report = ok(db::syncOutbox(s.local, {}, &last), s.name + ": final sync");
      commitMs.insert(commitMs.end(), report.commitMs.begin(), report.commitMs.end());
      if (report.complete()) break;
      if (tries == 50) die(s.name + ": the outbox does not empty");
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
  }
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();

  // Check: per student, the server holds exactly the answers the student's machine recorded.
  auto check = ok(db::openDatabase(o.server, serverOptions), "reopening the server");
  const auto progress = ok(db::classProgress(check, code, "coordinator"), "class progress");
  std::map<std::string, long> remoteAnswers;
  for (const auto& p : progress.students) remoteAnswers[p.userName] = p.answers;
  long lost = 0, duplicated = 0, onServer = 0;
  for (Student& s : students) {
    db::SqlProgressRepository mine(s.local);
    const long local = long(ok(mine.reviewResponses(s.userId), "reading back").size());
    if (local != o.answers) die(s.name + ": recorded " + std::to_string(local) + " answers locally");
    const long remote = remoteAnswers[s.name];
    onServer += remote;
    if (remote < local) lost += local - remote;
    if (remote > local) duplicated += remote - local;
  }
  std::printf("{\"students\": %d, \"answers_each\": %d, \"workers\": %d, \"restart\": \"%s\", \"down_s\": %.1f,"
              " \"failed_syncs_while_down\": %d, \"events_on_server\": %ld, \"events_total\": %lld,"
              " \"lost\": %ld, \"duplicated\": %ld, \"seconds\": %.2f, \"events_per_s\": %.0f, \"events_per_s_while_up\": %.0f,"
              " \"server_commits\": %zu, \"commit_ms_median\": %.2f, \"commit_ms_p99\": %.2f, \"commit_ms_max\": %.2f}\n",
              o.students, o.answers, o.workers, restartNote.c_str(), downFor, failedSyncs.load(), onServer,
              (long long)progress.events, lost, duplicated, seconds, double(onServer) / seconds,
              double(onServer) / std::max(1e-9, seconds - downFor), commitMs.size(),
              percentile(commitMs, 0.5), percentile(commitMs, 0.99), percentile(commitMs, 1.0));
  return lost == 0 && duplicated == 0 && progress.events == total ? 0 : 1;
}
