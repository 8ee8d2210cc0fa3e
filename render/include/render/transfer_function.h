// Transfer functions (ARCHITECTURE.md §4): 1-D RGBA splines an expert shapes, and the 2-D table the
// ray caster samples, built from a data TF and a distance TF by the paper's Algorithm 1.
#pragma once

#include <array>
#include <vector>

#include "core/error.h"

namespace at::render {

using Rgba = std::array<float, 4>;  // linear RGB and opacity, each 0..1

struct TfPoint {
  double x = 0;  // HU on the data axis; normalised distance 0..1 on the distance axis
  Rgba rgba{0, 0, 0, 0};
  bool operator==(const TfPoint&) const = default;
};

// A 1-D transfer function: control points sorted by x (strictly increasing), interpolated per
// channel by a monotone cubic (Fritsch–Carlson): it passes through every point, never overshoots
// between two points (a plateau stays flat, a ramp stays a ramp), and is constant beyond the ends.
class TransferFunction1D {
 public:
  TransferFunction1D() = default;
  // Errors: no points, x not strictly increasing, a channel outside 0..1 (message names the index).
  static Result<TransferFunction1D> fromPoints(std::vector<TfPoint> points);

  const std::vector<TfPoint>& points() const { return points_; }
  double xMin() const { return points_.front().x; }
  double xMax() const { return points_.back().x; }
  // Interpolated value at x, clamped to [0,1] per channel.
  Rgba evaluate(double x) const;
  // `n` evenly spaced samples from xMin to xMax inclusive (n ≥ 2).
  std::vector<Rgba> sample(int n) const;

 private:
  std::vector<TfPoint> points_;
  std::vector<std::array<double, 4>> slopes_;  // Fritsch–Carlson tangents per point and channel
};

// The paper's distance normalisation f(x) = 2 / (1 + α^x): 1 at the structure (x = 0), falling
// towards 0 as the weighted distance grows (α > 1). +infinity (unreachable) maps to 0.
float normaliseDistance(float distance, float alpha);

// A 2-D RGBA table: data axis (i, HU from dataMin to dataMax) × normalised-distance axis
// (j, 0..1). Row-major with i contiguous: value(i, j) = rgba[i + dataSize * j].
struct TransferFunction2D {
  int dataSize = 0, distanceSize = 0;
  double dataMin = 0, dataMax = 1;
  std::vector<Rgba> rgba;

  const Rgba& value(int i, int j) const { return rgba[std::size_t(i) + std::size_t(dataSize) * std::size_t(j)]; }
  // Bilinear lookup as the GPU does with a linear-filtered, edge-clamped texture.
  Rgba lookup(double hu, double normalisedDistance) const;
};

// Algorithm 1: for data sample i and distance sample j, κ = dist[j].A;
//   RGB = lerp(data[i].RGB, dist[j].RGB, κ);   A = lerp(t · data[i].A, data[i].A · dist[j].A, κ).
TransferFunction2D buildTransferFunction2D(const std::vector<Rgba>& data, const std::vector<Rgba>& dist, float t,
                                           double dataMin, double dataMax);
// Samples both 1-D TFs (dataSize, distanceSize entries) and applies Algorithm 1.
TransferFunction2D buildTransferFunction2D(const TransferFunction1D& data, const TransferFunction1D& dist, float t,
                                           int dataSize = 256, int distanceSize = 256);

}  // namespace at::render
