#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <vector>

#include "quiz/likert_stats.h"
#include "test_support.h"

using namespace at::quiz;

namespace {
// Brute-force two-sided exact Wilcoxon p-value: enumerate all 2^m sign assignments of the given
// (mid)ranks. Independent of the library's counting method.
double bruteForceWilcoxonP(const std::vector<double>& ranks, double observedWPlus) {
  const std::size_t m = ranks.size();
  double total = 0;
  for (double r : ranks) total += r;
  const double mean = total / 2.0;
  const double dev = std::fabs(observedWPlus - mean);
  std::size_t hits = 0;
  for (std::size_t mask = 0; mask < (std::size_t(1) << m); ++mask) {
    double w = 0;
    for (std::size_t i = 0; i < m; ++i)
      if (mask & (std::size_t(1) << i)) w += ranks[i];
    if (std::fabs(w - mean) >= dev - 1e-9) ++hits;
  }
  return double(hits) / double(std::size_t(1) << m);
}
}  // namespace

TEST_CASE("LikertSummary_ThreeRatingsOfFive_MatchesHandEnumeratedDistribution") {
  // Differences +2,+2,+2: all tied, midrank 2 each; W+ = 6. Under H0, W+ ∈ {0,2,4,6} with
  // counts 1,3,3,1 of 8; mean 3; |W+ − 3| ≥ 3 happens for W+ = 0 or 6 → p = 2/8.
  const LikertSummary s = summariseLikert({5, 5, 5});
  CHECK(s.n == 3);
  CHECK(s.mean == doctest::Approx(5.0));
  CHECK(s.sd == doctest::Approx(0.0));
  CHECK(s.wPlus == doctest::Approx(6.0));
  CHECK(s.exact);
  CHECK(s.pValue == doctest::Approx(0.25));
}

TEST_CASE("LikertSummary_MixedRatingsWithTies_MatchesHandComputedRanksAndBruteForceP") {
  // Ratings 1,2,4,1,5 → d = −2,−1,+1,−2,+2; |d| = 2,1,1,2,2 → midranks 4,1.5,1.5,4,4.
  // W+ = 1.5 (the +1) + 4 (the +2) = 5.5. Mean 2.6, SD sqrt(((1.6)²+(0.6)²+(1.4)²+(1.6)²+(2.4)²)/4).
  const LikertSummary s = summariseLikert({1, 2, 4, 1, 5});
  CHECK(s.wPlus == doctest::Approx(5.5));
  CHECK(s.mean == doctest::Approx(2.6));
  CHECK(s.sd == doctest::Approx(std::sqrt((2.56 + 0.36 + 1.96 + 2.56 + 5.76) / 4.0)));
  CHECK(s.pValue == doctest::Approx(bruteForceWilcoxonP({4, 1.5, 1.5, 4, 4}, 5.5)));
  // 95 % CI: mean ± t(4) · sd / √5, t(4) = 2.776445.
  CHECK(s.ciHigh - s.mean == doctest::Approx(2.776445 * s.sd / std::sqrt(5.0)).epsilon(1e-5));
}

TEST_CASE("LikertSummary_AllAtMidpoint_HasPOneAndNoNonZero") {
  const LikertSummary s = summariseLikert({3, 3, 3, 3});
  CHECK(s.nonZero == 0);
  CHECK(s.pValue == 1.0);
  CHECK(s.mean == doctest::Approx(3.0));
}

TEST_CASE("LikertSummary_Empty_HasZeroN") {
  const LikertSummary s = summariseLikert({});
  CHECK(s.n == 0);
  CHECK(s.pValue == 1.0);
}

TEST_CASE("LikertSummary_RandomSmallSamples_ExactPEqualsBruteForce") {
  std::mt19937_64 rng(at::test::freshSeed("LikertSummary_RandomSmallSamples"));
  std::uniform_int_distribution<int> rating(1, 5), size(1, 14);
  for (int trial = 0; trial < 40; ++trial) {
    std::vector<double> r(size(rng));
    for (double& v : r) v = rating(rng);
    const LikertSummary s = summariseLikert(r);
    // Recompute midranks independently: rank |d| among non-zero differences.
    std::vector<double> d;
    for (double v : r)
      if (v != 3) d.push_back(std::fabs(v - 3));
    std::vector<double> ranks;
    double wPlus = 0;
    std::size_t k = 0;
    for (double v : r) {
      if (v == 3) continue;
      double below = 0, equal = 0;
      for (double o : d) {
        below += o < std::fabs(v - 3);
        equal += o == std::fabs(v - 3);
      }
      const double midrank = below + (equal + 1) / 2.0;
      ranks.push_back(midrank);
      if (v > 3) wPlus += midrank;
      ++k;
    }
    CHECK(s.nonZero == k);
    CHECK(s.wPlus == doctest::Approx(wPlus));
    if (!ranks.empty()) CHECK(s.pValue == doctest::Approx(bruteForceWilcoxonP(ranks, wPlus)));
  }
}

TEST_CASE("LikertSummary_LargeSample_UsesNormalApproximationCloseToExact") {
  std::vector<double> r;
  for (int i = 0; i < 60; ++i) r.push_back(i % 5 == 0 ? 4 : (i % 3 == 0 ? 1 : 2));
  const LikertSummary approx = summariseLikert(r, 3.0, 10);
  const LikertSummary exact = summariseLikert(r, 3.0, 100);
  CHECK_FALSE(approx.exact);
  CHECK(exact.exact);
  CHECK(approx.pValue == doctest::Approx(exact.pValue).epsilon(0.25));
  CHECK(approx.pValue < 0.01);
}

TEST_CASE("StudentT975_KnownQuantiles") {
  CHECK(studentT975(1) == doctest::Approx(12.7062).epsilon(1e-4));
  CHECK(studentT975(10) == doctest::Approx(2.2281).epsilon(1e-4));
  CHECK(studentT975(30) == doctest::Approx(2.0423).epsilon(1e-4));
}
