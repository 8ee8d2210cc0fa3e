#include "render/transfer_function.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace at::render {

Result<TransferFunction1D> TransferFunction1D::fromPoints(std::vector<TfPoint> points) {
  if (points.empty()) return fail("transfer function has no control points");
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!std::isfinite(points[i].x)) return fail("point " + std::to_string(i) + ": x is not a finite number");
    if (i > 0 && !(points[i].x > points[i - 1].x))
      return fail("point " + std::to_string(i) + ": x must be greater than the previous point's x");
    for (float c : points[i].rgba)
      if (!(c >= 0.0f && c <= 1.0f)) return fail("point " + std::to_string(i) + ": rgba must be 4 numbers in 0..1");
  }
  TransferFunction1D tf;
  tf.points_ = std::move(points);
  const std::size_t n = tf.points_.size();
  tf.slopes_.assign(n, {0, 0, 0, 0});
  if (n >= 2) {
    for (int c = 0; c < 4; ++c) {
      std::vector<double> delta(n - 1);
      for (std::size_t k = 0; k + 1 < n; ++k)
        delta[k] = (tf.points_[k + 1].rgba[c] - tf.points_[k].rgba[c]) / (tf.points_[k + 1].x - tf.points_[k].x);
      std::vector<double> m(n);
      m[0] = delta[0];
      m[n - 1] = delta[n - 2];
      for (std::size_t k = 1; k + 1 < n; ++k)
        m[k] = (delta[k - 1] * delta[k] <= 0) ? 0.0 : 0.5 * (delta[k - 1] + delta[k]);
      // Fritsch–Carlson: limit the tangents so each segment stays monotone.
      for (std::size_t k = 0; k + 1 < n; ++k) {
        if (delta[k] == 0) {
          m[k] = 0;
          m[k + 1] = 0;
          continue;
        }
        const double a = m[k] / delta[k], b = m[k + 1] / delta[k];
        if (a < 0) m[k] = 0;
        if (b < 0) m[k + 1] = 0;
        const double s = a * a + b * b;
        if (s > 9) {
          const double tau = 3 / std::sqrt(s);
          m[k] = tau * a * delta[k];
          m[k + 1] = tau * b * delta[k];
        }
      }
      for (std::size_t k = 0; k < n; ++k) tf.slopes_[k][c] = m[k];
    }
  }
  return tf;
}

Rgba TransferFunction1D::evaluate(double x) const {
  if (points_.empty()) return {0, 0, 0, 0};
  if (x <= points_.front().x) return points_.front().rgba;
  if (x >= points_.back().x) return points_.back().rgba;
  const auto it = std::upper_bound(points_.begin(), points_.end(), x,
                                   [](double v, const TfPoint& p) { return v < p.x; });
  const std::size_t k = std::size_t(it - points_.begin()) - 1;
  const TfPoint& p0 = points_[k];
  const TfPoint& p1 = points_[k + 1];
  const double h = p1.x - p0.x, s = (x - p0.x) / h;
  const double h00 = (1 + 2 * s) * (1 - s) * (1 - s), h10 = s * (1 - s) * (1 - s);
  const double h01 = s * s * (3 - 2 * s), h11 = s * s * (s - 1);
  Rgba out;
  for (int c = 0; c < 4; ++c) {
    const double v = h00 * p0.rgba[c] + h10 * h * slopes_[k][c] + h01 * p1.rgba[c] + h11 * h * slopes_[k + 1][c];
    out[c] = float(std::clamp(v, 0.0, 1.0));
  }
  return out;
}

std::vector<Rgba> TransferFunction1D::sample(int n) const {
  std::vector<Rgba> out(std::size_t(std::max(n, 2)));
  const double span = xMax() - xMin();
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = evaluate(xMin() + span * double(i) / double(out.size() - 1));
  return out;
}

float normaliseDistance(float distance, float alpha) {
  if (std::isinf(distance)) return 0.0f;
  const double p = std::pow(double(alpha), double(distance));
  return float(2.0 / (1.0 + p));
}

Rgba TransferFunction2D::lookup(double hu, double normalisedDistance) const {
  // Texel centres at (i + 0.5) / size, as GL_LINEAR with CLAMP_TO_EDGE.
  const double u = (hu - dataMin) / (dataMax - dataMin);
  const double fi = std::clamp(u * (dataSize - 1), 0.0, double(dataSize - 1));
  const double fj = std::clamp(normalisedDistance * (distanceSize - 1), 0.0, double(distanceSize - 1));
  const int i0 = std::min(int(fi), dataSize - 1), j0 = std::min(int(fj), distanceSize - 1);
  const int i1 = std::min(i0 + 1, dataSize - 1), j1 = std::min(j0 + 1, distanceSize - 1);
  const double a = fi - i0, b = fj - j0;
  Rgba out;
  for (int c = 0; c < 4; ++c)
    out[c] = float((1 - a) * (1 - b) * value(i0, j0)[c] + a * (1 - b) * value(i1, j0)[c] +
                   (1 - a) * b * value(i0, j1)[c] + a * b * value(i1, j1)[c]);
  return out;
}

TransferFunction2D buildTransferFunction2D(const std::vector<Rgba>& data, const std::vector<Rgba>& dist, float t,
                                           double dataMin, double dataMax) {
  TransferFunction2D tf;
  tf.dataSize = int(data.size());
  tf.distanceSize = int(dist.size());
  tf.dataMin = dataMin;
  tf.dataMax = dataMax;
  tf.rgba.resize(data.size() * dist.size());
  const auto lerp = [](float a, float b, float k) { return a + (b - a) * k; };
  for (std::size_t j = 0; j < dist.size(); ++j) {
    const float kappa = dist[j][3];
    for (std::size_t i = 0; i < data.size(); ++i) {
      Rgba& o = tf.rgba[i + data.size() * j];
      for (int c = 0; c < 3; ++c) o[c] = lerp(data[i][c], dist[j][c], kappa);
      o[3] = lerp(t * data[i][3], data[i][3] * dist[j][3], kappa);
    }
  }
  return tf;
}

TransferFunction2D buildTransferFunction2D(const TransferFunction1D& data, const TransferFunction1D& dist, float t,
                                           int dataSize, int distanceSize) {
  // The distance axis always spans 0..1 whatever the control points cover.
  std::vector<Rgba> distSamples(std::size_t(std::max(distanceSize, 2)));
  for (std::size_t j = 0; j < distSamples.size(); ++j)
    distSamples[j] = dist.evaluate(double(j) / double(distSamples.size() - 1));
  double lo = data.xMin(), hi = data.xMax();
  if (!(hi > lo)) hi = lo + 1;
  std::vector<Rgba> dataSamples(std::size_t(std::max(dataSize, 2)));
  for (std::size_t i = 0; i < dataSamples.size(); ++i)
    dataSamples[i] = data.evaluate(lo + (hi - lo) * double(i) / double(dataSamples.size() - 1));
  return buildTransferFunction2D(dataSamples, distSamples, t, lo, hi);
}

}  // namespace at::render
