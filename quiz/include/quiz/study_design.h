// Counterbalancing for blinded A/B preference studies: the order of structures follows a balanced
// Latin square (Williams design) over participants, and which condition is shown as "A"
// alternates so that, over one full cycle of participants, every structure has each condition as
// "A" equally often. The seed permutes the structures before the square is applied; it is stored
// with the study so the design can be reproduced.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace at::quiz {

// Williams design for n items: n rows when n is even, 2n rows (square + mirrored square) when n is
// odd. Every item appears in every position equally often, and every ordered pair of distinct
// items is adjacent (i immediately before j) equally often. rows[r][position] = item index.
std::vector<std::vector<std::size_t>> williamsDesign(std::size_t n);

// Participants in one full counterbalancing cycle for n items (rows of the design, rounded up to
// an even number so the A/B alternation also balances).
std::size_t counterbalancingCycle(std::size_t n);

struct TrialPlan {
  std::size_t structureIndex = 0;  // index into the study's structure list
  std::size_t position = 0;        // presentation order, 0-based
  bool aIsFirstCondition = true;   // true: condition 0 (WDT) is shown as "A"
};

// The plan for the participant with 0-based enrolment index `participant`: structures in Latin
// square order (after a seeded permutation) and the A/B mapping for each.
std::vector<TrialPlan> planParticipant(std::size_t structureCount, std::size_t participant, std::uint64_t seed);

}  // namespace at::quiz
