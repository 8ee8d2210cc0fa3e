// Elo-style adaptation: an ability θ per user against a difficulty d per question, on one scale
// (1500 = average). After each answer both move by K·(score − expected), in opposite directions.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace at::quiz {

inline constexpr double kDefaultAbility = 1500;
inline constexpr double kDefaultEloK = 32;

// Probability that a user of ability θ answers a question of difficulty d: 1/(1+10^((d−θ)/400)).
double expectedScore(double ability, double difficulty);

struct EloUpdate {
  double ability = kDefaultAbility;
  double difficulty = 1500;
  double expected = 0.5;
};

// score in 0..1 (partial credit allowed). θ' = θ + K(s − E); d' = d − K(s − E).
EloUpdate updateElo(double ability, double difficulty, double score, double k = kDefaultEloK);

struct SelectionCandidate {
  std::string questionId;
  double difficulty = 1500;
  bool eligible = true;  // due for review or never answered; ineligible ones are never chosen
};

// Adaptive selection: among eligible candidates, the one whose expected score is nearest
// `targetSuccess`; ties (within 1e-9) broken by the smaller questionId. nullopt if none eligible.
std::optional<std::size_t> chooseAdaptive(const std::vector<SelectionCandidate>& candidates, double ability,
                                          double targetSuccess = 0.7);

}  // namespace at::quiz
