#include "terminal_answers.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/strings.h"
#include "quiz/answer_json.h"
#include "printable_output.h"

namespace at::app {

namespace {

using str::lower;
using str::trim;

// A pick on the question's picture (or at a point) as a locate answer.
Result<quiz::Answer> pickAnswer(const PickInput& input, const AskedQuestion& q) {
  if (q.serverPictureSize) {
    const auto [width, height] = *q.serverPictureSize;
    if (!input.pixel) return fail("a graded locate item is answered with the pixel x y on its picture, not a point in mm");
    const double x = std::floor((*input.pixel)[0]), y = std::floor((*input.pixel)[1]);
    if (x < 0 || y < 0 || x >= width || y >= height)
      return fail("the pixel (" + std::to_string(long(x)) + ", " + std::to_string(long(y)) + ") is outside the " +
                  std::to_string(width) + "×" + std::to_string(height) + " picture");
    quiz::Answer a;
    a.pick = quiz::Pick{};
    a.pick->pixel = std::array<int, 2>{int(x), int(y)};
    return a;
  }
  if (!q.views) {
    if (input.pixel) return fail("there is no picture to pick on (pictures are off): give a point as mm X Y Z");
    return fail("points in mm need the course's dataset, which did not load");
  }
  // A pixel is picked at its whole coordinates, as a class server grades it (from the pixel and the
  // view's id: the structure this machine finds under it is not believed there).
  quiz::Answer a;
  if (input.pixel) {
    const int x = int(std::floor((*input.pixel)[0])), y = int(std::floor((*input.pixel)[1]));
    auto pick = q.views->pickPixel(x, y, q.target);
    if (!pick) return tl::unexpected(pick.error());
    a.pick = *pick;
    a.pick->pixel = std::array<int, 2>{x, y};
    a.pick->view = q.views->lastViewId();
    return a;
  }
  auto pick = q.views->pickPointMm(*input.pointMm, q.target);
  if (!pick) return tl::unexpected(pick.error());
  a.pick = *pick;
  return a;
}

}  // namespace

void printWrapped(const std::string& text, int indent) {
  std::istringstream words(text);
  std::string word, line;
  const std::string pad(std::size_t(indent), ' ');
  while (words >> word) {
    if (!line.empty() && line.size() + 1 + word.size() > std::size_t(96 - indent)) {
      terminalPrintf("%s%s\n", pad.c_str(), line.c_str());
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
  }
  if (!line.empty()) terminalPrintf("%s%s\n", pad.c_str(), line.c_str());
}

FileAnswers::FileAnswers(std::string path) : path_(std::move(path)), in_(path_) {}

std::optional<std::string> FileAnswers::nextLine() {
  std::string line;
  while (std::getline(in_, line)) {
    ++lineNumber_;
    if (!trim(line).empty()) return line;
  }
  return std::nullopt;
}

std::string FileAnswers::where() const { return path_ + ":" + std::to_string(lineNumber_); }

std::optional<std::string> TerminalAnswers::nextLine() {
  terminalPrintf("  answer> ");
  std::fflush(stdout);
  std::string line;
  if (!std::getline(std::cin, line)) return std::nullopt;
  return line;
}

Result<std::unique_ptr<AnswerSource>> answerSource(const std::optional<std::string>& answersFile) {
  if (!answersFile) return std::unique_ptr<AnswerSource>(std::make_unique<TerminalAnswers>());
  auto file = std::make_unique<FileAnswers>(*answersFile);
  if (!file->ok()) return fail(ErrorKind::Io, "--answers " + *answersFile + ": cannot open");
  return std::unique_ptr<AnswerSource>(std::move(file));
}

std::string answerHint(const AskedQuestion& q) {
  switch (q.kind) {
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation:
      return "type the number of a choice (0 to " + std::to_string(q.choiceIds.empty() ? 0 : q.choiceIds.size() - 1) + ")";
    case quiz::QuestionKind::Name:
      return "type the structure's name";
    case quiz::QuestionKind::Locate:
      if (q.serverPictureSize) return "type the pixel where it is in the picture as x y (e.g. 180 135)";
      return q.views ? "type the pixel where it is in the picture as x y (e.g. 180 135), or a point as mm X Y Z"
                     : "type a point where it is as mm X Y Z (LPS millimetres)";
    case quiz::QuestionKind::Order:
      return "list the structures in the order met, by number or name, separated by commas (e.g. 2, 0, 1)";
  }
  return "type an answer";
}

Result<quiz::Answer> parseTypedAnswer(const std::string& raw, const AskedQuestion& q) {
  const std::string text = trim(raw);
  if (text.empty()) return fail(answerHint(q));
  if (text[0] == '{') return parseFileAnswer(text, q);
  quiz::Answer answer;
  switch (q.kind) {
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation: {
      char* end = nullptr;
      const long n = std::strtol(text.c_str(), &end, 10);
      if (*end != '\0') return fail(answerHint(q));
      answer.choice = int(n);
      break;
    }
    case quiz::QuestionKind::Name:
      answer.text = text;
      break;
    case quiz::QuestionKind::Locate: {
      auto input = parsePickInput(text);
      if (!input) return tl::unexpected(input.error());
      return pickAnswer(*input, q);
    }
    case quiz::QuestionKind::Order: {
      // Numbers of the listed choices or names, separated by commas; numbers alone may also be
      // separated by spaces ("2 0 1").
      const bool numbersOnly = text.find_first_not_of("0123456789, ") == std::string::npos;
      std::string list = text;
      if (numbersOnly) std::replace(list.begin(), list.end(), ' ', ',');
      std::vector<std::string> order;
      std::stringstream parts(list);
      std::string part;
      while (std::getline(parts, part, ',')) {
        const std::string entry = trim(part);
        if (entry.empty()) continue;
        if (entry.find_first_not_of("0123456789") == std::string::npos) {
          const unsigned long n = std::strtoul(entry.c_str(), nullptr, 10);
          if (n >= q.choiceIds.size()) {
            return fail("choice " + entry + " is not listed (0 to " +
                        std::to_string(q.choiceIds.empty() ? 0 : q.choiceIds.size() - 1) + ")");
          }
          order.push_back(q.choiceIds[n]);
          continue;
        }
        const auto it = q.idByName.find(lower(entry));
        order.push_back(it == q.idByName.end() ? entry : it->second);
      }
      if (order.empty()) return fail(answerHint(q));
      answer.order = std::move(order);
      break;
    }
  }
  return answer;
}

Result<quiz::Answer> parseFileAnswer(const std::string& line, const AskedQuestion& q) {
  const auto j = nlohmann::json::parse(line, nullptr, false);
  if (j.is_object() && (j.contains("pixel") || j.contains("point_mm"))) {
    if (q.kind != quiz::QuestionKind::Locate) return fail("\"pixel\" and \"point_mm\" answer locate questions only");
    if (j.size() != 1) return fail("give either \"pixel\": [x, y] or \"point_mm\": [x, y, z], nothing else");
    PickInput input;
    const auto& v = j.begin().value();
    const std::size_t n = j.contains("pixel") ? 2 : 3;
    if (!v.is_array() || v.size() != n) return fail(std::string(j.begin().key()) + ": must be " + std::to_string(n) + " numbers");
    for (const auto& x : v)
      if (!x.is_number()) return fail(std::string(j.begin().key()) + ": must be " + std::to_string(n) + " numbers");
    if (n == 2) input.pixel = std::array<double, 2>{v[0].get<double>(), v[1].get<double>()};
    else input.pointMm = Vec3{v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
    return pickAnswer(input, q);
  }
  return quiz::answerFromJson(line);
}

void printGrade(const quiz::Grade& grade) {
  std::string line;
  if (grade.correct) line = "✓ " + grade.feedback;
  else if (grade.score > 0) {
    char score[48];
    std::snprintf(score, sizeof score, " (score %.2f of 1)", grade.score);
    line = "◑ " + grade.feedback + score;
  } else {
    line = "✗ " + grade.feedback;
  }
  printWrapped(line, 2);
  std::fflush(stdout);
}

Result<Asked> askQuestion(AnswerSource& source, const AskedQuestion& question, const GiveAnswer& give, bool allowSkip,
                          bool allowBack) {
  const auto shownAt = std::chrono::steady_clock::now();
  while (true) {
    auto line = source.nextLine();
    if (!line) return Asked::InputEnded;
    const std::string word = lower(trim(*line));
    if (source.interactive() && word == "quit") return Asked::Quit;
    if (source.interactive() && allowSkip && word == "skip") return Asked::Skipped;
    if (source.interactive() && allowSkip && word == "finish") return Asked::Finish;
    if (allowBack && word == "back") return Asked::Back;
    auto answer = source.interactive() ? parseTypedAnswer(*line, question) : parseFileAnswer(*line, question);
    // Answers read from a file have no response time: 0 records "not measured" (never rated Easy).
    const auto latency = source.interactive() ? std::chrono::duration_cast<std::chrono::milliseconds>(
                                                    std::chrono::steady_clock::now() - shownAt)
                                              : std::chrono::milliseconds(0);
    Result<std::optional<quiz::Grade>> given =
        answer ? give(*answer, latency.count()) : Result<std::optional<quiz::Grade>>(tl::unexpected(answer.error()));
    if (given) {
      if (*given) printGrade(**given);
      return Asked::Answered;
    }
    // A bad answer names its line; a storage failure (a full disk) is not the line's fault.
    if (!source.interactive())
      return tl::unexpected(given.error().kind == ErrorKind::Io ? given.error()
                                                                : withContext(source.where(), given.error()));
    terminalPrintf("  %s — try again%s\n", given.error().message.c_str(), allowSkip ? " (or 'skip', 'finish')" : "");
    std::fflush(stdout);
  }
}

}  // namespace at::app
