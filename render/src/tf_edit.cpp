#include "render/tf_edit.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace at::render {

TfAxisRange dataAxisRange() { return {-32768, 32767, 1}; }
TfAxisRange distanceAxisRange() { return {0, 1, 1e-3}; }

Rgba clampRgba(Rgba rgba) {
  for (float& c : rgba) c = std::isnan(c) ? 0.0f : std::clamp(c, 0.0f, 1.0f);
  return rgba;
}

namespace {
Status checkIndex(const std::vector<TfPoint>& points, std::size_t index) {
  if (index >= points.size())
    return fail("transfer function: no point " + std::to_string(index) + " (it has " +
                std::to_string(points.size()) + " points)");
  return {};
}
}  // namespace

Result<std::size_t> addTfPoint(std::vector<TfPoint>& points, double x, Rgba rgba, const TfAxisRange& range) {
  if (!std::isfinite(x)) return fail("transfer function: a new point's x must be a finite number");
  x = std::clamp(x, range.xMin, range.xMax);
  auto it = std::lower_bound(points.begin(), points.end(), x, [](const TfPoint& p, double v) { return p.x < v; });
  const bool tooCloseAfter = it != points.end() && it->x - x < range.minGap;
  const bool tooCloseBefore = it != points.begin() && x - std::prev(it)->x < range.minGap;
  if (tooCloseAfter || tooCloseBefore)
    return fail("transfer function: a point already lies within " + std::to_string(range.minGap) + " of x = " +
                std::to_string(x));
  const std::size_t index = std::size_t(it - points.begin());
  points.insert(it, TfPoint{x, clampRgba(rgba)});
  return index;
}

Result<double> moveTfPoint(std::vector<TfPoint>& points, std::size_t index, double x, float alpha,
                           const TfAxisRange& range) {
  if (auto st = checkIndex(points, index); !st) return tl::unexpected(st.error());
  double lo = range.xMin, hi = range.xMax;
  if (index > 0) lo = std::max(lo, points[index - 1].x + range.minGap);
  if (index + 1 < points.size()) hi = std::min(hi, points[index + 1].x - range.minGap);
  if (lo > hi) lo = hi = points[index].x;  // squeezed by its neighbours: x stays
  if (std::isfinite(x)) points[index].x = std::clamp(x, lo, hi);
  points[index].rgba[3] = std::isnan(alpha) ? points[index].rgba[3] : std::clamp(alpha, 0.0f, 1.0f);
  return points[index].x;
}

Status deleteTfPoint(std::vector<TfPoint>& points, std::size_t index) {
  if (auto st = checkIndex(points, index); !st) return st;
  if (points.size() <= 2) return fail("transfer function: a spline keeps at least 2 points");
  points.erase(points.begin() + std::ptrdiff_t(index));
  return {};
}

Status setTfPointColour(std::vector<TfPoint>& points, std::size_t index, Rgba rgba) {
  if (auto st = checkIndex(points, index); !st) return st;
  points[index].rgba = clampRgba(rgba);
  return {};
}

std::optional<std::size_t> hitTestTfPoint(const std::vector<TfPoint>& points, double x, float alpha,
                                          double xTolerance, double alphaTolerance) {
  std::optional<std::size_t> best;
  double bestD = 1.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double dx = (points[i].x - x) / xTolerance, da = double(points[i].rgba[3] - alpha) / alphaTolerance;
    const double d = dx * dx + da * da;
    if (d <= bestD && (!best || d < bestD)) {
      best = i;
      bestD = d;
    }
  }
  return best;
}

std::vector<float> logHistogram(const std::vector<std::int16_t>& hu, int bins, double huMin, double huMax) {
  std::vector<float> out(std::size_t(std::max(bins, 0)), 0.0f);
  if (bins <= 0 || !(huMax > huMin)) return out;
  std::vector<std::uint64_t> counts(std::size_t(bins), 0);
  const double scale = double(bins) / (huMax - huMin);
  for (const std::int16_t v : hu) {
    const double f = (double(v) - huMin) * scale;
    if (f < 0 || f >= double(bins)) continue;
    ++counts[std::size_t(f)];
  }
  const std::uint64_t largest = *std::max_element(counts.begin(), counts.end());
  if (largest == 0) return out;
  const double norm = std::log1p(double(largest));
  for (std::size_t i = 0; i < counts.size(); ++i) out[i] = float(std::log1p(double(counts[i])) / norm);
  return out;
}

}  // namespace at::render
