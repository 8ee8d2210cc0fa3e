#include "quiz/likert_stats.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <numeric>

namespace at::quiz {

double normalCdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

namespace {

// Regularised incomplete beta I_x(a, b) by Lentz's continued fraction (Numerical-Recipes-style
// formulation of the standard expansion), accurate to ~1e-12 for the arguments used here.
double betaContinuedFraction(double a, double b, double x) {
  const double tiny = 1e-300;
  double c = 1.0, d = 1.0 - (a + b) * x / (a + 1.0);
  if (std::fabs(d) < tiny) d = tiny;
  d = 1.0 / d;
  double h = d;
  for (int m = 1; m <= 300; ++m) {
    const double m2 = 2.0 * m;
    double aa = m * (b - m) * x / ((a + m2 - 1.0) * (a + m2));
    d = 1.0 + aa * d;
    if (std::fabs(d) < tiny) d = tiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1.0 / d;
    h *= d * c;
    aa = -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1.0));
    d = 1.0 + aa * d;
    if (std::fabs(d) < tiny) d = tiny;
    c = 1.0 + aa / c;
    if (std::fabs(c) < tiny) c = tiny;
    d = 1.0 / d;
    const double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1.0) < 1e-14) break;
  }
  return h;
}

double incompleteBeta(double a, double b, double x) {
  if (x <= 0) return 0;
  if (x >= 1) return 1;
  const double lnFront = std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x);
  const double front = std::exp(lnFront);
  if (x < (a + 1.0) / (a + b + 2.0)) return front * betaContinuedFraction(a, b, x) / a;
  return 1.0 - front * betaContinuedFraction(b, a, 1.0 - x) / b;
}

// Two-sided tail probability P(|T| > t) for Student's t with df degrees of freedom.
double studentTwoSidedTail(double t, double df) { return incompleteBeta(df / 2.0, 0.5, df / (df + t * t)); }

}  // namespace

double studentT975(std::size_t df) {
  assert(df >= 1 && "studentT975: needs at least one degree of freedom");
  // Solve P(|T| > t) = 0.05 by bisection: the tail is monotone decreasing in t.
  double lo = 0.0, hi = 1000.0;
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (studentTwoSidedTail(mid, double(df)) > 0.05) lo = mid;
    else hi = mid;
  }
  return 0.5 * (lo + hi);
}

LikertSummary summariseLikert(const std::vector<double>& ratings, double midpoint, std::size_t exactLimit) {
  LikertSummary s;
  s.n = ratings.size();
  if (s.n == 0) return s;
  s.mean = std::accumulate(ratings.begin(), ratings.end(), 0.0) / double(s.n);
  s.ciLow = s.ciHigh = s.mean;
  if (s.n >= 2) {
    double ss = 0;
    for (double r : ratings) ss += (r - s.mean) * (r - s.mean);
    s.sd = std::sqrt(ss / double(s.n - 1));
    const double half = studentT975(s.n - 1) * s.sd / std::sqrt(double(s.n));
    s.ciLow = s.mean - half;
    s.ciHigh = s.mean + half;
  }

  // Wilcoxon signed-rank: drop zero differences, rank |d| with midranks.
  std::vector<double> diffs;
  for (double r : ratings)
    if (r != midpoint) diffs.push_back(r - midpoint);
  s.nonZero = diffs.size();
  if (diffs.empty()) {
    s.pValue = 1.0;
    return s;
  }
  std::vector<std::size_t> order(diffs.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return std::fabs(diffs[a]) < std::fabs(diffs[b]); });
  std::vector<double> rank(diffs.size());
  std::vector<std::size_t> tieSizes;
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j + 1 < order.size() && std::fabs(diffs[order[j + 1]]) == std::fabs(diffs[order[i]])) ++j;
    const double midrank = (double(i + 1) + double(j + 1)) / 2.0;
    for (std::size_t k = i; k <= j; ++k) rank[order[k]] = midrank;
    tieSizes.push_back(j - i + 1);
    i = j + 1;
  }
  for (std::size_t i = 0; i < diffs.size(); ++i)
    if (diffs[i] > 0) s.wPlus += rank[i];

  const std::size_t m = diffs.size();
  const double meanW = double(m) * double(m + 1) / 4.0;
  if (m <= exactLimit) {
    // Exact distribution of W+ under H0: each rank's sign is + or − with probability ½,
    // independently. Midranks are multiples of ½, so work in doubled ranks (integers) and count
    // the sign assignments reaching each doubled sum.
    std::vector<int> doubled(m);
    int total = 0;
    for (std::size_t i = 0; i < m; ++i) {
      doubled[i] = int(std::lround(rank[i] * 2.0));
      total += doubled[i];
    }
    std::vector<double> ways(std::size_t(total) + 1, 0.0);
    ways[0] = 1.0;
    int reach = 0;
    for (int r : doubled) {
      for (int v = reach; v >= 0; --v)
        if (ways[std::size_t(v)] != 0.0) ways[std::size_t(v + r)] += ways[std::size_t(v)];
      reach += r;
    }
    const double count = std::pow(2.0, double(m));
    // Two-sided: probability of a W+ at least as far from its mean as the observed one.
    const double observedDev = std::fabs(s.wPlus * 2.0 - meanW * 2.0);
    double tail = 0;
    for (int v = 0; v <= total; ++v)
      if (std::fabs(double(v) - meanW * 2.0) >= observedDev - 1e-9) tail += ways[std::size_t(v)];
    s.pValue = std::min(1.0, tail / count);
    s.exact = true;
  } else {
    double tieTerm = 0;
    for (std::size_t t : tieSizes) tieTerm += double(t) * double(t) * double(t) - double(t);
    const double var = double(m) * double(m + 1) * double(2 * m + 1) / 24.0 - tieTerm / 48.0;
    const double dev = std::fabs(s.wPlus - meanW);
    const double z = var > 0 ? std::max(0.0, dev - 0.5) / std::sqrt(var) : 0.0;
    s.pValue = std::min(1.0, 2.0 * (1.0 - normalCdf(z)));
    s.exact = false;
  }
  return s;
}

}  // namespace at::quiz
