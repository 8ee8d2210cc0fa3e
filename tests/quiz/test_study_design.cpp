#include <doctest/doctest.h>

#include <map>
#include <set>

#include "quiz/study_design.h"

using namespace at::quiz;

TEST_CASE("WilliamsDesign_EvenAndOdd_IsBalancedForPositionAndCarryover") {
  for (std::size_t n : {2u, 3u, 4u, 5u, 6u, 13u}) {
    CAPTURE(n);
    const auto rows = williamsDesign(n);
    CHECK(rows.size() == (n % 2 == 0 ? n : 2 * n));
    std::map<std::pair<std::size_t, std::size_t>, int> positionCount, pairCount;
    for (const auto& row : rows) {
      CHECK(std::set<std::size_t>(row.begin(), row.end()).size() == n);  // a permutation
      for (std::size_t p = 0; p < n; ++p) ++positionCount[{row[p], p}];
      for (std::size_t p = 0; p + 1 < n; ++p) ++pairCount[{row[p], row[p + 1]}];
    }
    const int perPosition = int(rows.size() / n);
    for (std::size_t item = 0; item < n; ++item)
      for (std::size_t p = 0; p < n; ++p) CHECK(positionCount[{item, p}] == perPosition);
    const int perPair = int(rows.size() * (n - 1) / (n * (n - 1)));
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = 0; b < n; ++b)
        if (a != b) CHECK(pairCount[{a, b}] == perPair);
  }
}

TEST_CASE("PlanParticipant_OverOneCycle_EachConditionIsAEquallyOftenAndPositionsBalance") {
  for (std::size_t n : {4u, 13u}) {
    CAPTURE(n);
    const std::size_t cycle = counterbalancingCycle(n);
    std::map<std::size_t, int> wdtAsA;
    std::map<std::pair<std::size_t, std::size_t>, int> atPosition;
    for (std::size_t participant = 0; participant < cycle; ++participant) {
      const auto plan = planParticipant(n, participant, 42);
      REQUIRE(plan.size() == n);
      for (const TrialPlan& t : plan) {
        wdtAsA[t.structureIndex] += t.aIsFirstCondition ? 1 : 0;
        ++atPosition[{t.structureIndex, t.position}];
      }
    }
    for (std::size_t s = 0; s < n; ++s) {
      CHECK(wdtAsA[s] * 2 == int(cycle));
      for (std::size_t p = 0; p < n; ++p) CHECK(atPosition[{s, p}] == int(cycle / n));
    }
  }
}

TEST_CASE("PlanParticipant_SameSeed_SamePlan_OtherSeed_OtherOrder") {
  const auto a = planParticipant(13, 5, 7), b = planParticipant(13, 5, 7), c = planParticipant(13, 5, 8);
  bool same = true, differs = false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    same = same && a[i].structureIndex == b[i].structureIndex && a[i].aIsFirstCondition == b[i].aIsFirstCondition;
    differs = differs || a[i].structureIndex != c[i].structureIndex;
  }
  CHECK(same);
  CHECK(differs);
}
