#include <doctest/doctest.h>

#include "lessons/scheduling.h"

using namespace at::lessons;

TEST_CASE("RatingFor_WrongIsAgainPartlyRightIsHardRightIsGoodFastIsEasy") {
  using K = at::quiz::QuestionKind;
  CHECK((ratingFor(false, 0, K::Locate, 2000) == Rating::Again));
  CHECK((ratingFor(false, 0.4, K::Order, 2000) == Rating::Again));
  CHECK((ratingFor(false, 0.5, K::Order, 2000) == Rating::Hard));
  CHECK((ratingFor(true, 1, K::Locate, 4001) == Rating::Good));
  CHECK((ratingFor(true, 1, K::Locate, 4000) == Rating::Easy));
  CHECK((ratingFor(true, 1, K::Name, 7000) == Rating::Easy));  // typing takes longer
  CHECK((ratingFor(true, 1, K::Order, 14000) == Rating::Easy));
  // Not measured (answers from a file): never Easy.
  CHECK((ratingFor(true, 1, K::Identify, 0) == Rating::Good));
}

TEST_CASE("ScheduleAnswer_MovesTheMemoryStateByFsrsAndCountsAnswers") {
  const Fsrs fsrs;
  StructureProgress p{.userId = 7, .structureId = "cochlea", .memory = {}};
  p = scheduleAnswer(p, Rating::Good, true, 1000, fsrs);
  CHECK((p.memory.phase == MemoryPhase::Learning));
  CHECK(p.memory.due == 1000 + 600);
  CHECK(p.answered == 1);
  CHECK(p.correct == 1);
  p = scheduleAnswer(p, Rating::Again, false, 2000, fsrs);
  CHECK(p.memory.due == 2000 + 60);
  CHECK(p.answered == 2);
  CHECK(p.correct == 1);
  CHECK(p.memory.lastReview == 2000);
  // The same history gives the same state (the fuzz is drawn from who, what and when).
  StructureProgress q{.userId = 7, .structureId = "cochlea", .memory = {}};
  q = scheduleAnswer(q, Rating::Good, true, 1000, fsrs);
  q = scheduleAnswer(q, Rating::Again, false, 2000, fsrs);
  CHECK(q.memory.due == p.memory.due);
  CHECK(q.memory.stability == p.memory.stability);
}

TEST_CASE("DueForReview_OrdersByDueTimeThenIdAndSkipsFutureAndUnanswered") {
  const auto at = [](const char* id, at::lessons::UnixSeconds due, int answered) {
    StructureProgress p{.userId = 1, .structureId = id, .memory = {}};
    p.memory.phase = answered ? MemoryPhase::Review : MemoryPhase::New;
    p.memory.due = due;
    p.answered = answered;
    return p;
  };
  std::vector<StructureProgress> all = {at("vestibule", 500, 3), at("cochlea", 100, 1), at("stapes", 9999, 2),
                                        at("incus", 100, 1), at("malleus", 0, 0)};
  const auto due = dueForReview(all, 1000);
  REQUIRE(due.size() == 3);
  CHECK(due[0].structureId == "cochlea");
  CHECK(due[1].structureId == "incus");
  CHECK(due[2].structureId == "vestibule");
}
