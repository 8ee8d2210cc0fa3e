#include "quiz/elo.h"

#include <cmath>

namespace at::quiz {

double expectedScore(double ability, double difficulty) {
  return 1.0 / (1.0 + std::pow(10.0, (difficulty - ability) / 400.0));
}

EloUpdate updateElo(double ability, double difficulty, double score, double k) {
  const double expected = expectedScore(ability, difficulty);
  const double delta = k * (score - expected);
  return EloUpdate{ability + delta, difficulty - delta, expected};
}

std::optional<std::size_t> chooseAdaptive(const std::vector<SelectionCandidate>& candidates, double ability,
                                          double targetSuccess) {
  std::optional<std::size_t> best;
  double bestGap = 0;
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    if (!candidates[i].eligible) continue;
    const double gap = std::abs(expectedScore(ability, candidates[i].difficulty) - targetSuccess);
    if (!best || gap < bestGap - 1e-9 ||
        (std::abs(gap - bestGap) <= 1e-9 && candidates[i].questionId < candidates[*best].questionId)) {
      best = i;
      bestGap = gap;
    }
  }
  return best;
}

}  // namespace at::quiz
