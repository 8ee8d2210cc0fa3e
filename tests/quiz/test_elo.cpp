#include <doctest/doctest.h>

#include "quiz/elo.h"

using namespace at::quiz;

TEST_CASE("ExpectedScore_IsOneHalfForEqualRatingsAndTenToOneFor400Points") {
  CHECK(expectedScore(1500, 1500) == doctest::Approx(0.5));
  CHECK(expectedScore(1900, 1500) == doctest::Approx(10.0 / 11.0));
  CHECK(expectedScore(1500, 1900) == doctest::Approx(1.0 / 11.0));
}

TEST_CASE("UpdateElo_ScriptedHistory_MatchesHandComputedNumbers") {
  // Hand computation (K = 32):
  //  1. θ=1500 vs d=1500, right:  E=0.5,      Δ=+16        → θ=1516,      d=1484
  //  2. θ=1516 vs d=1600, wrong:  E=0.381416, Δ=−12.205307 → θ=1503.7947, d=1612.2053
  //  3. θ=1503.7947 vs d=1400, half credit: E=0.645082, Δ=−4.642621 → θ=1499.1521, d=1404.6426
  EloUpdate u = updateElo(1500, 1500, 1.0);
  CHECK(u.expected == doctest::Approx(0.5));
  CHECK(u.ability == doctest::Approx(1516));
  CHECK(u.difficulty == doctest::Approx(1484));
  u = updateElo(u.ability, 1600, 0.0);
  CHECK(u.expected == doctest::Approx(0.381416).epsilon(1e-5));
  CHECK(u.ability == doctest::Approx(1503.7947).epsilon(1e-7));
  CHECK(u.difficulty == doctest::Approx(1612.2053).epsilon(1e-7));
  u = updateElo(u.ability, 1400, 0.5);
  CHECK(u.expected == doctest::Approx(0.645082).epsilon(1e-5));
  CHECK(u.ability == doctest::Approx(1499.1521).epsilon(1e-7));
  CHECK(u.difficulty == doctest::Approx(1404.6426).epsilon(1e-7));
}

TEST_CASE("UpdateElo_ConservesTheSumOfAbilityAndDifficulty") {
  for (double score : {0.0, 0.25, 1.0}) {
    const EloUpdate u = updateElo(1432, 1611, score, 24);
    CHECK(u.ability + u.difficulty == doctest::Approx(1432 + 1611));
  }
}

TEST_CASE("ChooseAdaptive_PicksExpectedSuccessNearestSeventyPercentAmongEligible") {
  // At θ=1500: d=1200 → 0.849, d=1353 → 0.700, d=1500 → 0.5, d=1650 → 0.297.
  std::vector<SelectionCandidate> c = {{"q.easy", 1200}, {"q.hard", 1650}, {"q.right", 1353}, {"q.even", 1500}};
  CHECK(chooseAdaptive(c, 1500) == std::optional<std::size_t>(2));
  c[2].eligible = false;  // not due: never chosen
  CHECK(chooseAdaptive(c, 1500) == std::optional<std::size_t>(0));  // |0.849−0.7| = 0.149 < |0.5−0.7| = 0.2
  // A stronger user: θ=1800 makes d=1650 the best match (0.703).
  CHECK(chooseAdaptive(c, 1800) == std::optional<std::size_t>(1));
  for (auto& x : c) x.eligible = false;
  CHECK_FALSE(chooseAdaptive(c, 1500).has_value());
}

TEST_CASE("ChooseAdaptive_TieBreaksBySmallerQuestionId") {
  std::vector<SelectionCandidate> c = {{"b", 1400}, {"a", 1400}, {"c", 1400}};
  CHECK(chooseAdaptive(c, 1500) == std::optional<std::size_t>(1));
}
