// Statistics for preference studies on a 1–5 Likert scale (the paper's Table 2: 1 = prefer WDT,
// 5 = prefer bare structure, 3 = no preference). Pure functions on plain vectors of ratings.
#pragma once

#include <cstddef>
#include <vector>

namespace at::quiz {

struct LikertSummary {
  std::size_t n = 0;
  double mean = 0;
  double sd = 0;              // sample standard deviation (n − 1); 0 when n < 2
  double ciLow = 0, ciHigh = 0;  // 95 % confidence interval of the mean (Student t); = mean when n < 2
  // Wilcoxon signed-rank test of the ratings against the scale midpoint (two-sided).
  std::size_t nonZero = 0;    // ratings ≠ midpoint (the others are dropped, as Wilcoxon does)
  double wPlus = 0;           // sum of ranks of ratings above the midpoint (midranks for ties)
  double pValue = 1;          // 1 when every rating equals the midpoint or n = 0
  bool exact = true;          // exact permutation distribution (with ties) or normal approximation
};

// Summarises ratings against `midpoint` (3 on a 1–5 scale). Exact Wilcoxon p-values (the
// permutation distribution of W+ given the observed midranks, so ties are handled exactly) when
// nonZero ≤ exactLimit; otherwise the normal approximation with tie correction and continuity
// correction.
LikertSummary summariseLikert(const std::vector<double>& ratings, double midpoint = 3.0,
                              std::size_t exactLimit = 50);

// Two-sided 97.5 % quantile of Student's t with `df` degrees of freedom (df ≥ 1).
double studentT975(std::size_t df);

// Standard normal cumulative distribution.
double normalCdf(double z);

}  // namespace at::quiz
