// Graded exams on a class server: the answer key never reaches a student's machine or login.
//
// An instructor or coordinator opens an exam for the class with its drawn items: what a student
// sees (prompt, choices, the scene to pick in, or for identify and name items the view as a
// picture, so the marked structure is never named) and, apart, what grades them (target, key
// choice, accepted names, tolerance), which the server keeps where no login can read it. A student
// sits the exam with their own login: each answer is sent and graded there, the grade written by
// the server; the student learns the results only after handing in. On a SQLite file (a laptop)
// none of this exists: an exam taken there is practice.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "db/connection.h"
#include "quiz/grading.h"

namespace at::db {

// One item as a student's machine receives it.
struct ClassExamItem {
  int position = 0;                  // 0-based
  std::string kind;                  // "locate", "identify", "name"
  std::string prompt;
  std::vector<std::string> choices;  // identify: structure ids in display order
  std::string locateView = "3d";     // locate: "3d" or "slice"
  std::string sceneJson = "{}";      // locate: the scene the picture shows (it does not mark the target)
  std::string pictureBase64;         // the item's view as a PNG (locate: the picture clicked on)
  int pictureWidth = 0, pictureHeight = 0;  // locate: the picture's size in pixels
};
// Pixels x_from..x_to (inclusive) of row y of a locate item's picture.
struct PixelRun {
  int y = 0, xFrom = 0, xTo = 0;
};
// What grades one item; stays on the server.
struct ClassExamKey {
  std::string questionId;
  std::string target;
  int keyChoice = -1;               // identify
  std::vector<std::string> names;   // name: accepted names (as written; kept for the record)
  double toleranceMm = 0;           // locate: a pick this near the target also counts
  // locate: the pixels of the item's picture whose click counts (the target under the click, or
  // within the tolerance), decided by the laptop's grader for every pixel where the exam is opened.
  std::vector<PixelRun> acceptedPixels;
  // name: what the server grades with, by the laptop's rule (quiz::gradeName): the target's and
  // every other structure's spellings without their side words (quiz::splitSide bodies), the
  // target's side ("left", "right" or "") and whether the question asks for it. setNameKey fills them.
  std::vector<std::string> nameBodies, competitorBodies;
  std::string targetSide;
  bool askSide = false;
};
// Fills `key`'s name fields for `question` (a Name question) from the laptop's grading context:
// names = the target's catalogue names and the question's synonyms.
void setNameKey(ClassExamKey& key, const quiz::ResolvedQuestion& question, const quiz::GradingContext& context);

struct ClassExamOpening {
  std::string examId, courseId, title;
  std::int64_t timeLimitS = 0;
  std::optional<double> passScore;
  std::vector<ClassExamItem> items;
  std::vector<ClassExamKey> keys;   // one per item, same order
  std::vector<std::string> prerequisites;  // lesson ids a member finishes (on the server) before starting
};
// Opens the exam in the class (instructors and coordinators; `by` as in class_accounts.h).
// Conflict when it was opened before; Invalid when a locate item lacks its picture or pixels.
// Returns the number of items.
Result<int> openClassExam(Database& server, const std::string& code, const ClassExamOpening& exam,
                          const std::optional<std::string>& by);
// Closes it: no new sittings; open ones are handed in. Returns how many were.
Result<int> closeClassExam(Database& server, const std::string& code, const std::string& examId,
                           const std::optional<std::string>& by);
// Whether the exam has been opened in the class and is not closed (false on a SQLite file).
Result<bool> classExamOpen(Database& server, const std::string& code, const std::string& examId);

struct ClassExamSitting {
  std::string examId, title;
  std::int64_t deadline = 0;        // Unix seconds (the server's clock)
  std::int64_t serverNow = 0;       // the server's clock when the sitting was read
  std::optional<double> passScore;
  std::vector<ClassExamItem> items;
  std::set<int> answered;           // positions
  bool handedIn = false;            // this member's sitting is finished (finishClassExam gives its results)
};
// Starts the member's sitting (or returns the one started). Refused while the exam's prerequisite
// lessons are not finished on the server.
Result<ClassExamSitting> startClassExam(Database& server, const std::string& code, const std::string& examId,
                                        const std::optional<std::string>& by);

// Exactly the member for the item's kind.
struct ClassExamAnswer {
  std::optional<int> choice;          // identify
  std::optional<std::string> text;    // name
  std::optional<std::array<int, 2>> pixel;  // locate: the pixel (x, y) clicked on the item's picture
  std::int64_t latencyMs = 0;
};
// Sends one answer; the server grades and keeps it and says nothing about the grade.
Status answerClassExam(Database& server, const std::string& code, const std::string& examId, int position,
                       const ClassExamAnswer& answer, const std::optional<std::string>& by);

struct ClassExamItemResult {
  int position = 0;
  bool answered = false, correct = false;
  double score = 0;
};
struct ClassExamResult {
  double score = 0;
  std::optional<bool> passed;
  std::vector<ClassExamItemResult> items;
};
// Hands the member's sitting in; the server scores it. Returns the results (read back as the member).
Result<ClassExamResult> finishClassExam(Database& server, const std::string& code, const std::string& examId,
                                        const std::optional<std::string>& by);

// One sitting as an instructor sees it (`class progress`, xapi).
struct ClassExamSittingRow {
  std::string userName, examId, courseId;
  std::int64_t startedAt = 0;
  std::optional<std::int64_t> finishedAt;
  std::optional<double> score;
  std::optional<bool> passed;
};
Result<std::vector<ClassExamSittingRow>> classExamSittings(Database& server, const std::string& code);

// One graded answer as an instructor sees it (xapi): the item as shown, the answer as given (JSON:
// {choice}, {text} or {pixel: [x, y]}) and the server's grade.
struct ClassExamAnswerRow {
  std::string userName, examId;
  int position = 0;
  std::string kind;
  std::vector<std::string> choices;
  std::string answerJson;
  bool correct = false;
  double score = 0;
  std::int64_t latencyMs = 0, answeredAt = 0;
};
Result<std::vector<ClassExamAnswerRow>> classExamAnswers(Database& server, const std::string& code);

}  // namespace at::db
