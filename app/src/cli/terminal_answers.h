// Reading answers in the terminal, shared by `play` (lessons and reviews) and `exam`: where answers
// come from (a JSON-lines file or typed lines), how a typed line or a file line becomes a
// quiz::Answer for the question asked, and how the grade is printed.
//
// Typed forms: a choice's number; a name; structures by number or name separated by commas (order
// questions; numbers alone also by spaces: "2 0 1"); for locate questions a pick on the question's
// picture — "x y" (a pixel) or "mm X Y Z" (a point in LPS millimetres) — never a name. Every JSON form of quiz/answer_json.h is accepted too, and two
// more for locate questions: {"pixel": [x, y]} and {"point_mm": [x, y, z]}.
#pragma once

#include <cstdint>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "quiz/grading.h"
#include "quiz/question.h"
#include "terminal_views.h"
#include "volume/error.h"

namespace at::app {

// Prints `text` wrapped at ~96 columns with `indent` spaces in front of every line.
void printWrapped(const std::string& text, int indent);

// Where answers come from: a JSON-lines file (line numbers reported) or the terminal.
class AnswerSource {
 public:
  virtual ~AnswerSource() = default;
  // nullopt at the end of input. Blank file lines are skipped; a blank typed line is returned.
  virtual std::optional<std::string> nextLine() = 0;
  virtual std::string where() const = 0;  // "answers.jsonl:7" or "stdin"
  virtual bool interactive() const = 0;
};

class FileAnswers final : public AnswerSource {
 public:
  explicit FileAnswers(std::string path);
  bool ok() const { return bool(in_); }
  std::optional<std::string> nextLine() override;
  std::string where() const override;
  bool interactive() const override { return false; }

 private:
  std::string path_;
  std::ifstream in_;
  int lineNumber_ = 0;
};

class TerminalAnswers final : public AnswerSource {
 public:
  std::optional<std::string> nextLine() override;
  std::string where() const override { return "stdin"; }
  bool interactive() const override { return true; }
};

// The answers of --answers FILE when given, else the terminal. Error: the file cannot be opened.
Result<std::unique_ptr<AnswerSource>> answerSource(const std::optional<std::string>& answersFile);

// The question being answered, as the answer readers need it.
struct AskedQuestion {
  quiz::QuestionKind kind = quiz::QuestionKind::Locate;
  std::string target;                    // locate: the structure whose distance a pick measures
  std::vector<std::string> choiceIds;    // identify, relation
  std::map<std::string, std::string> idByName;  // lower-case names and ids → structure id (order)
  TerminalViews* views = nullptr;        // locate: the picture picks are made on (null: none)
  // locate on a class server: the size of the item's picture as received; a pick is the pixel
  // itself (Pick::pixel), graded on the server, and a point in mm is refused.
  std::optional<std::array<int, 2>> serverPictureSize;
};

// What to type, for an empty or unreadable line.
std::string answerHint(const AskedQuestion& question);

// A typed line (plain forms or JSON) or a file line (JSON) as an answer to `question`.
Result<quiz::Answer> parseTypedAnswer(const std::string& line, const AskedQuestion& question);
Result<quiz::Answer> parseFileAnswer(const std::string& line, const AskedQuestion& question);

// The grade as one coherent line: "✓ Correct: …", "✗ Not quite: …", or for partial credit
// "◑ Partly right: … (score 0.67 of 1)".
void printGrade(const quiz::Grade& grade);

enum class Asked { Answered, Skipped, Finish, Quit, InputEnded, Back };

// Reads answers to `question` until `give` accepts one (it records it; it returns the grade to
// print, or nullopt when grades are held back, as in exams). Interactive input may retry after a
// bad answer, and with `allowSkip` (exams) 'skip' leaves the question and 'finish' hands in; from a
// file a bad answer is an error naming its line. 'quit' stops. With `allowBack` (lessons) 'back',
// typed or a file line, goes to the previous step. Answers read from a file are recorded as
// untimed (latency 0).
using GiveAnswer = std::function<Result<std::optional<quiz::Grade>>(const quiz::Answer&, std::int64_t latencyMs)>;
Result<Asked> askQuestion(AnswerSource& source, const AskedQuestion& question, const GiveAnswer& give,
                          bool allowSkip = false, bool allowBack = false);

}  // namespace at::app
