#include "quiz/study_design.h"

#include <algorithm>
#include <numeric>

namespace at::quiz {

std::vector<std::vector<std::size_t>> williamsDesign(std::size_t n) {
  std::vector<std::vector<std::size_t>> rows;
  if (n == 0) return rows;
  // First row: 0, 1, n−1, 2, n−2, 3, … ; row r adds r (mod n) to every entry.
  std::vector<std::size_t> first;
  first.push_back(0);
  for (std::size_t step = 1; first.size() < n; ++step) {
    first.push_back(step);
    if (first.size() < n) first.push_back(n - step);
  }
  for (std::size_t r = 0; r < n; ++r) {
    std::vector<std::size_t> row(n);
    for (std::size_t p = 0; p < n; ++p) row[p] = (first[p] + r) % n;
    rows.push_back(row);
  }
  if (n % 2 == 1) {
    for (std::size_t r = 0; r < n; ++r) {
      std::vector<std::size_t> mirrored(rows[r].rbegin(), rows[r].rend());
      rows.push_back(mirrored);
    }
  }
  return rows;
}

std::size_t counterbalancingCycle(std::size_t n) {
  if (n == 0) return 0;
  const std::size_t rows = n % 2 == 0 ? n : 2 * n;
  return rows % 2 == 0 ? rows : rows * 2;
}

namespace {
// splitmix64: a small, portable PRNG so the same seed gives the same permutation everywhere.
std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}
}  // namespace

std::vector<TrialPlan> planParticipant(std::size_t structureCount, std::size_t participant, std::uint64_t seed) {
  std::vector<TrialPlan> plan;
  if (structureCount == 0) return plan;
  std::vector<std::size_t> permutation(structureCount);
  std::iota(permutation.begin(), permutation.end(), 0);
  std::uint64_t state = seed;
  for (std::size_t i = structureCount - 1; i > 0; --i)  // Fisher–Yates
    std::swap(permutation[i], permutation[splitmix64(state) % (i + 1)]);

  const auto design = williamsDesign(structureCount);
  const std::size_t cycle = counterbalancingCycle(structureCount);
  const std::size_t inCycle = participant % cycle;
  const auto& row = design[inCycle % design.size()];
  for (std::size_t position = 0; position < structureCount; ++position) {
    TrialPlan t;
    t.structureIndex = permutation[row[position]];
    t.position = position;
    // Alternate by participant and item: over a cycle (an even number of participants) each item
    // has condition 0 as "A" for exactly half of the participants.
    t.aIsFirstCondition = (inCycle + row[position]) % 2 == 0;
    plan.push_back(t);
  }
  return plan;
}

}  // namespace at::quiz
