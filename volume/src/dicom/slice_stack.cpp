// Pure geometry of slice stacks (no DCMTK): sorting along the normal, spacing, tilt, gaps.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "dicom_support.h"

namespace at::dicom {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Two positions closer than this along the normal are the same slice position.
constexpr double kSamePositionMm = 0.01;

// Tolerance when comparing slice distances: DS values carry about 6 significant digits.
double spacingTolerance(double spacingMm) { return std::max(0.01, 0.01 * spacingMm); }

Vec3 normalised(const Vec3& v) {
  const double n = norm(v);
  return n > 0 ? (1.0 / n) * v : v;
}

std::string joinMm(const std::vector<double>& values) {
  std::string out;
  for (std::size_t i = 0; i < values.size(); ++i) out += (i ? ", " : "") + formatNumber(values[i]);
  return out + " mm";
}

}  // namespace

std::string formatNumber(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.3f", value);
  std::string s = buffer;
  while (!s.empty() && s.back() == '0') s.pop_back();
  if (!s.empty() && s.back() == '.') s.pop_back();
  if (s == "-0") s = "0";
  return s;
}

Status checkOrientation(const Vec3& row, const Vec3& column) {
  const double rowLength = norm(row), columnLength = norm(column);
  if (std::abs(rowLength - 1) > 1e-3 || std::abs(columnLength - 1) > 1e-3)
    return fail("ImageOrientationPatient holds non-unit direction cosines (lengths " + formatNumber(rowLength) +
                " and " + formatNumber(columnLength) + ")");
  const double cosine = dot(row, column) / (rowLength * columnLength);
  if (std::abs(cosine) > 1e-3) {
    const double angle = std::acos(std::clamp(cosine, -1.0, 1.0)) * 180 / kPi;
    return fail("ImageOrientationPatient rows and columns are not orthogonal (" + formatNumber(angle) +
                "°): sheared or tilted images are not supported");
  }
  return {};
}

Result<SliceStack> stackSlices(const StackInput& input) {
  const std::size_t n = input.positionsMm.size();
  if (n == 0) return fail("no slices");
  SliceStack stack;
  stack.normal = normalised(cross(input.row, input.column));
  stack.sliceOf.assign(n, 0);

  std::vector<double> along(n);
  for (std::size_t i = 0; i < n; ++i) along[i] = dot(input.positionsMm[i], stack.normal);
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return along[a] < along[b]; });
  const std::size_t first = order.front();
  stack.originMm = input.positionsMm[first];

  // Gantry tilt: every slice must lie on the line through the first one along the normal.
  double worstOffset = 0, worstAngle = 0;
  std::size_t worst = first;
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 d = input.positionsMm[i] - stack.originMm;
    const double a = dot(d, stack.normal);
    const double sideways = norm(d - a * stack.normal);
    if (sideways > 0.01 + 1e-3 * std::abs(a) && sideways > worstOffset) {
      worstOffset = sideways;
      worstAngle = std::atan2(sideways, std::abs(a)) * 180 / kPi;
      worst = i;
    }
  }
  if (worstOffset > 0)
    return fail("gantry tilt: slice positions advance at " + formatNumber(worstAngle) +
                "° to the slice normal (" + input.names[worst] + " lies " + formatNumber(worstOffset) +
                " mm off the normal through " + input.names[first] + "); tilted series are not supported");

  // Distinct positions along the normal.
  std::vector<double> distinct;                  // position of each distinct slice
  std::vector<std::size_t> distinctOf(n);        // input slice → distinct index
  std::vector<std::size_t> representative;       // one input slice per distinct position
  for (std::size_t idx = 0; idx < n; ++idx) {
    const std::size_t i = order[idx];
    if (!distinct.empty() && along[i] - distinct.back() <= kSamePositionMm) {
      if (!input.allowRepeatsAndGaps)
        return fail(input.names[representative.back()] + " and " + input.names[i] +
                    " lie at the same slice position (" + formatNumber(along[i]) + " mm along the normal)");
      distinctOf[i] = distinct.size() - 1;
      continue;
    }
    distinct.push_back(along[i]);
    representative.push_back(i);
    distinctOf[i] = distinct.size() - 1;
  }

  const std::size_t m = distinct.size();
  if (m == 1) {
    stack.sliceCount = 1;
    stack.spacingMm = input.nominalSpacingMm > 0 ? input.nominalSpacingMm : 1.0;
    return stack;
  }
  std::vector<double> gaps(m - 1);
  for (std::size_t j = 0; j + 1 < m; ++j) gaps[j] = distinct[j + 1] - distinct[j];

  // The base spacing: the nominal one if every gap is a multiple of it (SEG), otherwise the most
  // common gap (series) or the smallest gap (SEG, whose frames may skip empty slices).
  auto multipleOf = [](double gap, double base) {
    const double k = std::round(gap / base);
    return k >= 1 && std::abs(gap - k * base) <= spacingTolerance(base) ? int(k) : 0;
  };
  double base = 0;
  if (input.allowRepeatsAndGaps) {
    if (input.nominalSpacingMm > 0 &&
        std::all_of(gaps.begin(), gaps.end(), [&](double g) { return multipleOf(g, input.nominalSpacingMm) > 0; }))
      base = input.nominalSpacingMm;
    else
      base = *std::min_element(gaps.begin(), gaps.end());
  } else {
    std::size_t bestCount = 0;
    for (double candidate : gaps) {
      const std::size_t count = std::count_if(gaps.begin(), gaps.end(), [&](double g) {
        return std::abs(g - candidate) <= spacingTolerance(candidate);
      });
      if (count > bestCount || (count == bestCount && candidate < base)) {
        bestCount = count;
        base = candidate;
      }
    }
  }

  // Guards the int slice indices below against absurd positions in broken headers.
  const double span = distinct.back() - distinct.front();
  if (!(base > 0) || span / base > 1e8)
    return fail("slice positions span " + formatNumber(span) + " mm at a spacing of " + formatNumber(base) +
                " mm: implausibly many slices");

  // Distinct gap values (clustered) for messages.
  auto distinctGaps = [&]() {
    std::vector<double> sorted = gaps, values;
    std::sort(sorted.begin(), sorted.end());
    for (double g : sorted)
      if (values.empty() || g - values.back() > spacingTolerance(values.back())) values.push_back(g);
    return values;
  };

  bool allMultiples = true;
  int missing = 0;
  std::size_t firstGap = m;
  for (std::size_t j = 0; j + 1 < m; ++j) {
    const int k = multipleOf(gaps[j], base);
    if (k == 0) allMultiples = false;
    else if (k > 1) {
      missing += k - 1;
      if (firstGap == m) firstGap = j;
    }
  }
  if (!allMultiples) {
    if (input.allowRepeatsAndGaps)
      return fail("frame positions are unevenly spaced (distances " + joinMm(distinctGaps()) + ")");
    return fail("uneven slice spacing: " + std::to_string(distinctGaps().size()) +
                " different distances between slice positions (" + joinMm(distinctGaps()) + ")");
  }
  if (missing > 0 && !input.allowRepeatsAndGaps)
    return fail("missing slices: gap of " + formatNumber(gaps[firstGap]) + " mm between " +
                input.names[representative[firstGap]] + " and " + input.names[representative[firstGap + 1]] +
                " where the spacing is " + formatNumber(base) + " mm (" + std::to_string(missing) +
                (missing == 1 ? " slice" : " slices") + " missing)");

  std::vector<int> kOfDistinct(m, 0);
  for (std::size_t j = 1; j < m; ++j) kOfDistinct[j] = kOfDistinct[j - 1] + multipleOf(gaps[j - 1], base);
  stack.sliceCount = kOfDistinct.back() + 1;
  // The mean distance over the whole stack is more precise than any single DS-rounded gap.
  stack.spacingMm = (distinct.back() - distinct.front()) / kOfDistinct.back();
  for (std::size_t i = 0; i < n; ++i) stack.sliceOf[i] = kOfDistinct[distinctOf[i]];
  return stack;
}

}  // namespace at::dicom
