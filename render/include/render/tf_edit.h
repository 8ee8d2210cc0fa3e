// Editing a 1-D transfer function's control points (the expert's spline editor, ARCHITECTURE.md §4),
// kept free of any UI so the rules can be tested: every edit leaves the points valid for
// TransferFunction1D::fromPoints and parsePreset (x strictly increasing, inside the axis range and at
// least `minGap` apart; every channel in 0..1).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "render/transfer_function.h"
#include "core/error.h"

namespace at::render {

// The x range an axis allows and the smallest spacing kept between neighbouring points.
struct TfAxisRange {
  double xMin = 0, xMax = 1;
  double minGap = 1e-3;
};
TfAxisRange dataAxisRange();      // HU: -32768..32767 (what presets accept), points ≥ 1 HU apart
TfAxisRange distanceAxisRange();  // normalised distance 0..1, points ≥ 0.001 apart

// Clamps every channel to 0..1 (NaN becomes 0).
Rgba clampRgba(Rgba rgba);

// Inserts a point at x (clamped into the range) with the colour clamped to 0..1, keeping the order.
// Error when x is closer than minGap to an existing point. Returns the new point's index.
Result<std::size_t> addTfPoint(std::vector<TfPoint>& points, double x, Rgba rgba, const TfAxisRange& range);

// Moves point `index` to x and opacity `alpha`: x is clamped into the range and strictly between
// its neighbours (minGap from each), so points never swap order; alpha is clamped to 0..1.
// Error when index is out of range. Returns the x actually used.
Result<double> moveTfPoint(std::vector<TfPoint>& points, std::size_t index, double x, float alpha,
                           const TfAxisRange& range);

// Removes point `index`. Error when index is out of range or when it would leave fewer than 2 points.
Status deleteTfPoint(std::vector<TfPoint>& points, std::size_t index);

// Sets point `index`'s colour and opacity (clamped to 0..1). Error when index is out of range.
Status setTfPointColour(std::vector<TfPoint>& points, std::size_t index, Rgba rgba);

// The point nearest to (x, alpha) within the tolerances (an ellipse of half-axes xTolerance and
// alphaTolerance), or nullopt when none is that close. Ties go to the lower index.
std::optional<std::size_t> hitTestTfPoint(const std::vector<TfPoint>& points, double x, float alpha,
                                          double xTolerance, double alphaTolerance);

// Counts of `hu` values in `bins` equal bins over [huMin, huMax) (values outside are ignored),
// mapped to log(1 + count) / log(1 + largest count) so bars are 0..1 and sparse bins stay visible.
std::vector<float> logHistogram(const std::vector<std::int16_t>& hu, int bins, double huMin, double huMax);

}  // namespace at::render
