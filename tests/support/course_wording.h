// The wording checks every shipped course's student-facing texts pass, whatever its dataset (the
// phantom's in tests/lessons/test_course_phantom.cpp, the skull CT's in tests/app/test_skull_course.cpp):
// a structure's name inside a sentence is written as quiz::nameInSentence writes it ("Click the
// cochlea", not "Click the Cochlea"), and no text uses the program's own vocabulary (WDT, voxels,
// presets, seeds ...) that a first-year student has not met. Read: the course's and lessons'
// titles and summaries, show steps' titles and texts, question prompts and explanations, the
// feedback to a right and a wrong answer of every question, and every exam item's prompt.
#pragma once

#include <doctest/doctest.h>

#include <cctype>
#include <string>
#include <utility>
#include <vector>

#include "lessons/curriculum.h"
#include "lessons/exam.h"
#include "lessons/lesson_engine.h"
#include "quiz/grading.h"
#include "quiz/keys.h"
#include "quiz/name_matching.h"
#include "volume/structure.h"

namespace at::test {

// Where `text` writes a structure's display name capitalised in the middle of a sentence (the
// name as written where nameInSentence would lower-case it, not at the start of the text or after
// '.', '!', '?' or ':'): "Locate the Cochlea in the view." → "Cochlea".
inline std::vector<std::string> capitalisedMidSentence(const std::string& text, const std::vector<Structure>& structures) {
  std::vector<std::string> found;
  for (const Structure& s : structures) {
    const std::string& name = s.displayName;
    if (name.empty() || quiz::nameInSentence(name) == name) continue;
    for (std::size_t at = text.find(name); at != std::string::npos; at = text.find(name, at + 1)) {
      const std::size_t after = at + name.size();
      if (after < text.size() && std::isalpha(static_cast<unsigned char>(text[after]))) continue;  // a longer word
      std::size_t before = at;
      while (before > 0 && (text[before - 1] == ' ' || text[before - 1] == '"' || text[before - 1] == '(')) --before;
      if (before > 0 && std::isalpha(static_cast<unsigned char>(text[at - 1]))) continue;  // inside a word
      if (before == 0 || std::string(".!?:").find(text[before - 1]) != std::string::npos) continue;
      found.push_back(name);
    }
  }
  return found;
}

// The program's own words in `text` (whole words, any case): how the view is made (WDT, voxel,
// preset, transfer function, opacity), how the labels were made (seeds, grown, threshold, label
// map) — a student reads anatomy, and "weighted distance" is the one rendering idea the courses
// teach. "HU" only where the same text says "Hounsfield".
inline std::vector<std::string> jargonIn(const std::string& text) {
  static const std::vector<std::string> words = {"wdt",  "voxel",  "voxels",    "preset", "presets", "transfer function",
                                                 "opacity", "seed", "seeds", "grown", "threshold", "label map",
                                                 "isosurface", "hu"};
  std::string lower = text;
  for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
  const auto isWordChar = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
  std::vector<std::string> found;
  for (const std::string& w : words) {
    if (w == "hu" && lower.find("hounsfield") != std::string::npos) continue;
    for (std::size_t at = lower.find(w); at != std::string::npos; at = lower.find(w, at + 1)) {
      const bool starts = at == 0 || !isWordChar(lower[at - 1]);
      const bool ends = at + w.size() == lower.size() || !isWordChar(lower[at + w.size()]);
      if (starts && ends) {
        found.push_back(w);
        break;
      }
    }
  }
  return found;
}

// The right answer to a resolved question, as a student would give it.
inline quiz::Answer rightAnswerTo(const quiz::ResolvedQuestion& q, const std::vector<Structure>& structures) {
  quiz::Answer a;
  switch (q.question.kind) {
    case quiz::QuestionKind::Locate: a.pick = quiz::Pick{q.question.target, 0, std::nullopt, ""}; break;
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation: a.choice = q.keyChoice; break;
    case quiz::QuestionKind::Name:
      for (const Structure& s : structures)
        if (s.id == q.question.target) a.text = s.displayName;
      break;
    case quiz::QuestionKind::Order: a.order = q.keyOrder; break;
  }
  return a;
}

// A wrong answer to a resolved question: another structure, another choice, an unknown name.
inline quiz::Answer wrongAnswerTo(const quiz::ResolvedQuestion& q, const std::vector<Structure>& structures) {
  quiz::Answer a;
  switch (q.question.kind) {
    case quiz::QuestionKind::Locate:
      a.pick = quiz::Pick{q.question.target == structures.front().id ? structures.back().id : structures.front().id, 7.5, std::nullopt, ""};
      break;
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation: a.choice = (q.keyChoice + 1) % int(q.choices.size()); break;
    case quiz::QuestionKind::Name: a.text = "no such structure"; break;
    case quiz::QuestionKind::Order: a.order = {q.keyOrder.rbegin(), q.keyOrder.rend()}; break;
  }
  return a;
}

// Checks every student-facing text of `course` (on the dataset whose structures and keys are
// given) with doctest CHECKs naming the place and the text; returns how many texts were read.
inline int checkCourseWording(const lessons::Course& course, const std::vector<Structure>& structures, quiz::KeyComputer& keys) {
  int texts = 0;
  const auto check = [&](const std::string& where, const std::string& text) {
    ++texts;
    CHECK_MESSAGE(capitalisedMidSentence(text, structures).empty(), where << ": " << text);
    const auto jargon = jargonIn(text);
    CHECK_MESSAGE(jargon.empty(), where << ": '" << (jargon.empty() ? "" : jargon.front()) << "' in: " << text);
  };
  check(course.id + " title", course.title);
  check(course.id + " summary", course.summary);
  const quiz::GradingContext context = lessons::gradingContext(structures, course);
  for (const lessons::Lesson& lesson : course.lessons) {
    check(lesson.id + " title", lesson.title);
    check(lesson.id + " summary", lesson.summary);
    for (const lessons::Step& step : lesson.steps) {
      if (step.kind == lessons::StepKind::Show) {
        check(lesson.id + " show title", step.show.title);
        check(lesson.id + " show", step.show.text);
        continue;
      }
      if (step.kind != lessons::StepKind::Question) continue;
      check(step.question.id, step.question.prompt);
      check(step.question.id + " explanation", step.question.explanation);
      auto resolved = quiz::resolveQuestion(step.question, keys);
      REQUIRE_MESSAGE(resolved, (resolved ? "" : resolved.error().message));
      for (const quiz::Answer& answer : {rightAnswerTo(*resolved, structures), wrongAnswerTo(*resolved, structures)}) {
        auto graded = quiz::grade(*resolved, answer, context);
        REQUIRE_MESSAGE(graded, (graded ? "" : graded.error().message));
        check(step.question.id + " feedback", graded->feedback);
      }
    }
  }
  for (lessons::ExamSpec exam : course.exams) {
    exam.count = int(exam.structures.size() * exam.kinds.size());  // every structure × kind
    for (const char* seed : {"wording-a", "wording-b"}) {
      auto items = lessons::drawExamItems(exam, structures, keys, seed);
      REQUIRE_MESSAGE(items, (items ? "" : items.error().message));
      for (const lessons::ExamItem& item : *items) check(item.question.question.id, item.question.question.prompt);
    }
  }
  return texts;
}

}  // namespace at::test
