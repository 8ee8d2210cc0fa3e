// A class on a class server (a PostgreSQL database every member's machine reaches) and the
// offline-first path of its learning records to it.
//
// On the server: a class has a code (what students type to join) and members with a role —
// students learn, instructors see the class's progress, coordinators also give roles. The
// server keeps class events: every answer, lesson start and lesson end a member's machine sent,
// each once (keyed by the UUID the machine minted), append-only; what an instructor sees is
// computed from them on every read, so events arriving late or twice change nothing but what
// they add.
//
// On a learner's machine (the local SQLite file): once a local user has joined a class, every
// answer, review answer, lesson start and lesson end of that user is written, in the same
// transaction as the record itself, into the outbox as an event with a fresh UUID. syncOutbox
// pushes what the server does not have yet whenever it is reachable; while it is not, learning
// goes on locally and the events wait. A push the server committed but this machine did not hear
// about is pushed again and ignored there: no loss, no duplicates.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "db/connection.h"

namespace at::db {

enum class ClassRole { Student, Instructor, Coordinator };
const char* toString(ClassRole role);  // "student", "instructor", "coordinator"
Result<ClassRole> parseClassRole(const std::string& text);

// A class code as typed (case and separators ignored: "k7m2-p9qx" is "K7M2P9QX"); an Invalid
// error naming the code when it cannot be one (8 of the letters and digits codes are made of).
Result<std::string> normalizeClassCode(const std::string& text);

struct ClassInfo {
  std::string code;
  std::string title;
  std::string createdBy;
};

// ---- On the server ----------------------------------------------------------------------------

// A new class with a fresh code; `creator` becomes its coordinator.
Result<ClassInfo> createClass(Database& server, const std::string& title, const std::string& creator);
// NotFound when no class has this code.
Result<ClassInfo> findClass(Database& server, const std::string& code);
// Joins `userName` to the class as a student. Joining again keeps the role the member has.
// Returns the member's role.
Result<ClassRole> joinClass(Database& server, const std::string& code, const std::string& userName);
// The member's role; NotFound when `userName` is not a member (or the class does not exist).
Result<ClassRole> memberRole(Database& server, const std::string& code, const std::string& userName);
// A coordinator of the class (`by`) gives `userName` (a member, or someone new) a role.
// Conflict when `by` is not a coordinator of it.
Status setMemberRole(Database& server, const std::string& code, const std::string& by, const std::string& userName,
                     ClassRole role);

// One student's work in a class, computed from the class events the server has.
struct StudentClassProgress {
  std::string userName;
  int answers = 0;          // lesson and review answers the server graded (waiting and practice left out)
  int correct = 0;          // of those, right as the server graded them
  int ungraded = 0;         // answers besides those, waiting for their keys (`class keys`); not practice
  int practice = 0;         // answers the server keeps as practice (locate picks it cannot grade)
  int structures = 0;       // distinct structures of the graded answers
  int lessonsStarted = 0;   // distinct lessons
  int lessonsFinished = 0;  // distinct lessons finished at least once
  std::optional<std::int64_t> lastActive;  // Unix seconds of the newest event; none yet: nullopt
  std::optional<std::string> withdrawal;   // withdrawn or excluded: the reason given
  int examsHandedIn = 0;                   // graded exams on the server (db/class_exams.h) handed in
  std::optional<double> examScore;         // their mean score; none handed in: nullopt
};
// How the class did on one structure.
struct StructureClassProgress {
  std::string structureId;
  int students = 0;  // students with a graded answer about it (waiting and practice left out)
  int answers = 0;
  int correct = 0;
};
struct ClassProgress {
  ClassInfo info;
  std::vector<StudentClassProgress> students;    // every student member, by name (none yet: zeros)
  std::vector<StructureClassProgress> structures;  // by structure id
  std::int64_t events = 0;                        // all events the server holds for the class
};
// What an instructor sees: only for instructors and coordinators of the class (Conflict naming
// `viewer`'s role otherwise, NotFound when `viewer` is not a member).
Result<ClassProgress> classProgress(Database& server, const std::string& code, const std::string& viewer);

// ---- On a learner's machine -------------------------------------------------------------------

struct ClassMembership {
  std::string userName;   // the local user
  std::string classCode;
  std::string server;     // the class server's URL as given
  ClassRole role = ClassRole::Student;
};
// Remembers that the local user joined a class (replacing an earlier one: events already in the
// outbox still go to the class they were written for).
Status rememberMembership(Database& local, const ClassMembership& membership);
Result<std::optional<ClassMembership>> membershipOf(Database& local, const std::string& userName);

struct OutboxCounts {
  std::int64_t pending = 0;  // not yet on the server
  std::int64_t sent = 0;     // on the server, or refused by it
  std::int64_t refused = 0;  // answered by the server with a reason it did not count them (kept in the outbox)
};
Result<OutboxCounts> outboxCounts(Database& local);

struct SyncOptions {
  int batchSize = 200;             // events per server transaction
  int connectTimeoutSeconds = 3;   // per server (libpq's minimum is 2)
};
struct ServerSync {
  std::string server;        // without its password
  std::int64_t pushed = 0;   // events the server did not have
  std::int64_t repeated = 0; // events it already had (an earlier push whose answer was lost)
  std::int64_t refused = 0;  // events the server did not count (not from this login, lesson locked, …)
  std::vector<std::string> refusals;  // the server's reasons, the first five
  std::int64_t pending = 0;  // still waiting afterwards
  std::optional<Error> error;  // why it stopped (Unavailable: not reachable now)
};
struct SyncReport {
  std::vector<ServerSync> servers;
  std::vector<double> commitMs;  // each server transaction, from BEGIN to its COMMIT's answer
  bool complete() const;         // nothing left pending and no error
};
// Open connections to class servers, kept between syncs by a program that syncs after every
// answer (a connection costs an authentication round; a dropped one is opened again).
class ServerConnections {
 public:
  ServerConnections();
  ~ServerConnections();
  ServerConnections(ServerConnections&&) noexcept;
  ServerConnections& operator=(ServerConnections&&) noexcept;
  // The open connection to `url`, opened now when there is none.
  Result<Database*> get(const std::string& url, int connectTimeoutSeconds);
  // Closes the connection to `url` (after it failed).
  void drop(const std::string& url);

 private:
  struct Open;
  std::unique_ptr<Open> open_;
};

// Pushes the outbox's pending events to their servers, oldest first, in transactions of
// `batchSize`; each batch is marked sent locally only after the server committed it. A server
// that cannot be reached (or drops the connection) stops that server's push with its error in
// the report; the events wait for the next sync. Errors of the local database are returned.
// `connections`: where to keep server connections between calls (none: opened and closed here).
Result<SyncReport> syncOutbox(Database& local, const SyncOptions& options = {},
                              ServerConnections* connections = nullptr);

}  // namespace at::db
