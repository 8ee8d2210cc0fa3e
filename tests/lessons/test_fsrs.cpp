// FSRS-6 against the reference implementation's published vectors (py-fsrs tests, fsrs-rs
// inference tests) and the properties its formulas promise.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include "lessons/fsrs.h"
#include "test_support.h"

using namespace at::lessons;

namespace {

// 2022-11-29 12:30:00 UTC, the reference tests' start.
constexpr UnixSeconds kStart = 1669725000;
constexpr UnixSeconds kDay = 86400;

FsrsParameters noFuzz() {
  FsrsParameters p;
  p.enableFuzz = false;
  return p;
}

}  // namespace

TEST_CASE("Fsrs_ReferenceIntervals_GoodSixAgainTwoGoodFive_AtDueTimes") {
  const Fsrs fsrs(noFuzz());
  const std::vector<Rating> ratings = {Rating::Good, Rating::Good, Rating::Good, Rating::Good, Rating::Good,
                                       Rating::Good, Rating::Again, Rating::Again, Rating::Good, Rating::Good,
                                       Rating::Good, Rating::Good, Rating::Good};
  MemoryState card;
  UnixSeconds at = kStart;
  std::vector<int> intervals;
  for (Rating r : ratings) {
    card = fsrs.review(card, r, at);
    intervals.push_back(Fsrs::elapsedDays(card.lastReview, card.due));
    at = card.due;
  }
  CHECK(intervals == std::vector<int>{0, 2, 11, 46, 163, 498, 0, 0, 2, 4, 7, 12, 21});
}

TEST_CASE("Fsrs_ReferenceMemoryState_AgainThenGoodFive_AtDayOffsets") {
  const std::vector<Rating> ratings = {Rating::Again, Rating::Good, Rating::Good, Rating::Good, Rating::Good, Rating::Good};
  const std::vector<int> offsets = {0, 0, 1, 3, 8, 21};
  const auto walk = [&](const Fsrs& fsrs) {
    MemoryState card;
    UnixSeconds at = kStart;
    for (std::size_t i = 0; i < ratings.size(); ++i) {
      at += offsets[i] * kDay;
      card = fsrs.review(card, ratings[i], at);
    }
    return card;
  };
  const MemoryState card = walk(Fsrs(noFuzz()));
  CHECK(std::abs(card.stability - 53.62691) < 1e-4);
  CHECK(std::abs(card.difficulty - 6.3574867) < 1e-4);
  // fsrs-rs's companion vector: the same history with the same-day terms (w17..w19) off.
  FsrsParameters frozen = noFuzz();
  frozen.w[17] = frozen.w[18] = frozen.w[19] = 0;
  const MemoryState withoutShortTerm = walk(Fsrs(frozen));
  CHECK(std::abs(withoutShortTerm.stability - 53.335106) < 1e-4);
  CHECK(std::abs(withoutShortTerm.difficulty - 6.3574867) < 1e-4);
}

TEST_CASE("Fsrs_FirstAnswer_TakesInitialStabilityAndDifficultyPerRating") {
  const Fsrs fsrs;
  const double s0[] = {0.212, 1.2931, 2.3065, 8.2956};
  const double d0[] = {6.4133, 5.11217071, 2.11810397, 1.0};
  int i = 0;
  for (Rating r : {Rating::Again, Rating::Hard, Rating::Good, Rating::Easy}) {
    const MemoryState card = fsrs.review(MemoryState{}, r, kStart);
    CHECK(card.stability == doctest::Approx(s0[i]));
    CHECK(card.difficulty == doctest::Approx(d0[i]).epsilon(1e-6));
    ++i;
  }
}

TEST_CASE("Fsrs_LearningSteps_OneAndTenMinutesThenGraduate") {
  const Fsrs fsrs(noFuzz());
  MemoryState card = fsrs.review(MemoryState{}, Rating::Good, kStart);
  CHECK((card.phase == MemoryPhase::Learning));
  CHECK(card.step == 1);
  CHECK(card.due - kStart == 600);
  CHECK(fsrs.review(MemoryState{}, Rating::Again, kStart).due - kStart == 60);
  CHECK(fsrs.review(MemoryState{}, Rating::Hard, kStart).due - kStart == 330);
  const MemoryState easy = fsrs.review(MemoryState{}, Rating::Easy, kStart);
  CHECK((easy.phase == MemoryPhase::Review));
  CHECK(easy.due - kStart >= kDay);
  card = fsrs.review(card, Rating::Good, card.due);
  CHECK((card.phase == MemoryPhase::Review));
  CHECK(card.due - card.lastReview >= kDay);
  // A lapse goes to Relearning for 10 minutes and is counted.
  const MemoryState lapsed = fsrs.review(card, Rating::Again, card.due);
  CHECK((lapsed.phase == MemoryPhase::Relearning));
  CHECK(lapsed.due - lapsed.lastReview == 600);
  CHECK(lapsed.lapses == 1);
  CHECK(lapsed.stability < card.stability);
}

TEST_CASE("Fsrs_RepeatedEasy_BottomsOutDifficultyAtOne") {
  const Fsrs fsrs(noFuzz());
  MemoryState card;
  for (int i = 0; i < 10; ++i) card = fsrs.review(card, Rating::Easy, kStart);
  CHECK(card.difficulty == 1.0);
}

TEST_CASE("Fsrs_Retrievability_IsNinetyPercentAfterOneStability") {
  const Fsrs fsrs;
  MemoryState card;
  CHECK(fsrs.retrievability(card, kStart) == 0);
  card.phase = MemoryPhase::Review;
  card.stability = 10;
  card.difficulty = 5;
  card.lastReview = kStart;
  CHECK(fsrs.retrievability(card, kStart) == doctest::Approx(1.0));
  CHECK(fsrs.retrievability(card, kStart + 10 * kDay) == doctest::Approx(0.9));
  CHECK(fsrs.retrievability(card, kStart + 30 * kDay) < 0.9);
  // At the desired retention of 0.9 the interval equals the stability.
  CHECK(fsrs.nextIntervalDays(10.0) == 10);
  CHECK(fsrs.nextIntervalDays(0.2) == 1);
}

TEST_CASE("Fsrs_Fuzz_StaysInTheReferenceRangeAndLeavesShortIntervalsAlone") {
  FsrsParameters p;
  p.enableFuzz = true;
  const Fsrs fsrs(p);
  std::mt19937_64 rng(at::test::freshSeed("Fsrs_Fuzz"));
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 200; ++i) {
    const double x = u(rng);
    CHECK(fsrs.fuzzedIntervalDays(2, x) == 2);
    const int f = fsrs.fuzzedIntervalDays(100, x);
    CHECK(f >= 93);  // delta = 1 + 0.15·4.5 + 0.1·13 + 0.05·80 = 6.975: 93..107
    CHECK(f <= 107);
  }
}

TEST_CASE("Fsrs_Validate_NamesTheParameterOutOfBounds") {
  FsrsParameters p;
  CHECK(validate(p));
  p.w[20] = 0.95;
  auto bad = validate(p);
  REQUIRE(!bad);
  CHECK(bad.error().message.find("w20") != std::string::npos);
  p = {};
  p.desiredRetention = 1.0;
  CHECK(!validate(p));
}
