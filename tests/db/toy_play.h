// Playing the toy course (toy_course.h) through a LessonEngine in tests: the right answer to each
// question, and a player that answers the current lesson to its end.
#pragma once

#include <doctest/doctest.h>

#include <functional>

#include "lessons/lesson_engine.h"
#include "toy_course.h"

namespace at::test {

// The answer that is right for a resolved question (names from `structures`).
inline quiz::Answer rightAnswer(const quiz::ResolvedQuestion& q,
                                const std::vector<Structure>& structures = toyStructures()) {
  quiz::Answer a;
  switch (q.question.kind) {
    case quiz::QuestionKind::Locate: a.pick = quiz::Pick{q.question.target, 0.0, std::nullopt, ""}; break;
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation: a.choice = q.keyChoice; break;
    case quiz::QuestionKind::Order: a.order = q.keyOrder; break;
    case quiz::QuestionKind::Name:
      for (const auto& s : structures)
        if (s.id == q.question.target) a.text = s.displayName;
      break;
  }
  return a;
}

// An answer that is wrong for any toy question (a structure name nobody has, a pick of nothing).
inline quiz::Answer wrongAnswer(const quiz::ResolvedQuestion& q) {
  quiz::Answer a;
  switch (q.question.kind) {
    case quiz::QuestionKind::Locate: a.pick = quiz::Pick{"", 0.0, std::nullopt, ""}; break;
    case quiz::QuestionKind::Identify:
    case quiz::QuestionKind::Relation: a.choice = q.keyChoice == 0 ? 1 : 0; break;
    case quiz::QuestionKind::Order: a.order = {q.keyOrder.rbegin(), q.keyOrder.rend()}; break;
    case quiz::QuestionKind::Name: a.text = "no such structure"; break;
  }
  return a;
}

// Plays the current lesson to the end (or `stopAfter` answers); the n-th answer (from 0) is right
// when `right(n)`. Returns the answers given.
inline int playAnswering(lessons::LessonEngine& engine, const std::function<bool(int)>& right,
                         int stopAfter = 1 << 30) {
  int answered = 0;
  while (!engine.atEnd()) {
    auto view = engine.current();
    REQUIRE(view);
    if (view->kind == lessons::StepKind::Question) {
      if (answered == stopAfter) return answered;
      auto q = engine.currentQuestion();
      REQUIRE(q);
      lessons::RenderState render{"p", "wdt", 0.25, 1.5, 0.75};
      const bool wantRight = right(answered);
      auto grade = engine.answer(wantRight ? rightAnswer(*q) : wrongAnswer(*q), render, 1200);
      REQUIRE_MESSAGE(grade, (grade ? "" : grade.error().message));
      CHECK(grade->correct == wantRight);
      ++answered;
    }
    REQUIRE(engine.next());
  }
  return answered;
}

// Plays the current lesson to the end (or `stopAfter` answers), answering right.
inline int playRight(lessons::LessonEngine& engine, int stopAfter = 1 << 30) {
  return playAnswering(engine, [](int) { return true; }, stopAfter);
}

}  // namespace at::test
