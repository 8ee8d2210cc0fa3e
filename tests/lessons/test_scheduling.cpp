#include <doctest/doctest.h>

#include "lessons/scheduling.h"

using namespace at::lessons;

TEST_CASE("Leitner_RightAnswersClimbBoxesWithDoublingIntervals") {
  const LeitnerSchedule s;
  StructureProgress p{7, "cochlea"};
  p = scheduleAnswer(p, true, 1000, s);  // first answer right: box 2, 2 days
  CHECK(p.box == 2);
  CHECK(p.dueAt == 1000 + 2 * 86400);
  p = scheduleAnswer(p, true, 2000, s);
  CHECK(p.box == 3);
  CHECK(p.dueAt == 2000 + 4 * 86400);
  p = scheduleAnswer(p, true, 3000, s);
  p = scheduleAnswer(p, true, 4000, s);
  CHECK(p.box == 5);
  CHECK(p.dueAt == 4000 + 16 * 86400);
  p = scheduleAnswer(p, true, 5000, s);  // stays in the last box
  CHECK(p.box == 5);
  CHECK(p.dueAt == 5000 + 16 * 86400);
  CHECK(p.answered == 5);
  CHECK(p.correct == 5);
  CHECK(p.lastAnsweredAt == 5000);
}

TEST_CASE("Leitner_WrongAnswerSendsBackToBoxOneAndComesBackSooner") {
  const LeitnerSchedule s;
  StructureProgress p{7, "stapes"};
  p.box = 4;
  p.dueAt = 0;
  p = scheduleAnswer(p, false, 10000, s);
  CHECK(p.box == 1);
  CHECK(p.dueAt == 10000 + 600);
  CHECK(p.correct == 0);
  CHECK(p.answered == 1);
  p = scheduleAnswer(p, true, 20000, s);  // relearned: box 2
  CHECK(p.box == 2);
  CHECK(p.dueAt == 20000 + 2 * 86400);
  // a first answer that is wrong: box 1 as well, and due before a right first answer would be
  StructureProgress fresh{7, "incus"};
  CHECK(scheduleAnswer(fresh, false, 0, s).dueAt < scheduleAnswer(fresh, true, 0, s).dueAt);
}

TEST_CASE("DueForReview_OrdersByDueTimeThenIdAndSkipsFutureAndUnanswered") {
  std::vector<StructureProgress> all = {
      {1, "vestibule", 2, 500, 3, 2, 0}, {1, "cochlea", 1, 100, 1, 0, 0}, {1, "stapes", 3, 9999, 2, 2, 0},
      {1, "incus", 2, 100, 1, 1, 0},     {1, "malleus", 0, 0, 0, 0, 0}};
  const auto due = dueForReview(all, 1000);
  REQUIRE(due.size() == 3);
  CHECK(due[0].structureId == "cochlea");
  CHECK(due[1].structureId == "incus");
  CHECK(due[2].structureId == "vestibule");
}
