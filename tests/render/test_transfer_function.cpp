#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <random>

#include "render/transfer_function.h"
#include "test_support.h"

using namespace at::render;

TEST_CASE("f(x) = 2/(1+alpha^x) matches hand-computed values") {
  CHECK(normaliseDistance(0.0f, 1.6f) == doctest::Approx(1.0));
  CHECK(normaliseDistance(1.0f, 1.6f) == doctest::Approx(2.0 / 2.6));
  CHECK(normaliseDistance(2.0f, 3.0f) == doctest::Approx(0.2));            // 2/(1+9)
  CHECK(normaliseDistance(3.0f, 2.0f) == doctest::Approx(2.0 / 9.0));      // 2/(1+8)
  CHECK(normaliseDistance(std::numeric_limits<float>::infinity(), 1.6f) == 0.0f);
}

TEST_CASE("Algorithm 1 blends data and distance TFs as the paper states, for hand-computed entries") {
  const std::vector<Rgba> data{{0.2f, 0.4f, 0.6f, 0.5f}, {1.0f, 1.0f, 1.0f, 0.8f}};
  const std::vector<Rgba> dist{{0, 0, 0, 0}, {1.0f, 0.0f, 0.0f, 0.25f}, {0, 1, 0, 1}};
  const TransferFunction2D tf = buildTransferFunction2D(data, dist, 0.4f, -1000, 1000);
  REQUIRE(tf.dataSize == 2);
  REQUIRE(tf.distanceSize == 3);
  // κ = 0: colour of the data, A = t·data.A.
  CHECK(tf.value(0, 0)[0] == doctest::Approx(0.2));
  CHECK(tf.value(0, 0)[3] == doctest::Approx(0.4 * 0.5));
  // κ = 0.25: RGB = 0.75·data + 0.25·dist; A = lerp(t·a, a·0.25, 0.25).
  CHECK(tf.value(0, 1)[0] == doctest::Approx(0.75 * 0.2 + 0.25 * 1.0));
  CHECK(tf.value(0, 1)[1] == doctest::Approx(0.75 * 0.4));
  CHECK(tf.value(0, 1)[3] == doctest::Approx(0.75 * 0.2 + 0.25 * (0.5 * 0.25)));
  CHECK(tf.value(1, 1)[3] == doctest::Approx(0.75 * 0.32 + 0.25 * (0.8 * 0.25)));
  // κ = 1: the distance colour and A = data.A·dist.A.
  CHECK(tf.value(1, 2)[0] == doctest::Approx(0.0));
  CHECK(tf.value(1, 2)[1] == doctest::Approx(1.0));
  CHECK(tf.value(1, 2)[3] == doctest::Approx(0.8));
}

TEST_CASE("t = 0 hides everything the distance TF does not reach; t = 1 keeps the data TF's opacity far away") {
  const std::vector<Rgba> data{{1, 1, 1, 0.6f}};
  const std::vector<Rgba> dist{{0, 0, 0, 0}, {1, 0, 0, 1}};
  CHECK(buildTransferFunction2D(data, dist, 0.0f, 0, 1).value(0, 0)[3] == 0.0f);
  CHECK(buildTransferFunction2D(data, dist, 1.0f, 0, 1).value(0, 0)[3] == doctest::Approx(0.6));
}

TEST_CASE("TransferFunction1D passes through its points and never overshoots between them") {
  const auto seed = at::test::freshSeed("tf1d_monotone");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0, 1);
  std::vector<TfPoint> pts;
  double x = -1000;
  for (int i = 0; i < 8; ++i) {
    x += 50 + 300 * u(rng);
    pts.push_back({x, {u(rng), u(rng), u(rng), u(rng)}});
  }
  auto tf = TransferFunction1D::fromPoints(pts);
  REQUIRE(tf);
  for (const TfPoint& p : pts)
    for (int c = 0; c < 4; ++c) CHECK(tf->evaluate(p.x)[std::size_t(c)] == doctest::Approx(p.rgba[std::size_t(c)]));
  for (std::size_t k = 0; k + 1 < pts.size(); ++k)
    for (int s = 1; s < 20; ++s) {
      const double xs = pts[k].x + (pts[k + 1].x - pts[k].x) * s / 20.0;
      const Rgba v = tf->evaluate(xs);
      for (int c = 0; c < 4; ++c) {
        const float lo = std::min(pts[k].rgba[std::size_t(c)], pts[k + 1].rgba[std::size_t(c)]);
        const float hi = std::max(pts[k].rgba[std::size_t(c)], pts[k + 1].rgba[std::size_t(c)]);
        CHECK(v[std::size_t(c)] >= lo - 1e-5f);
        CHECK(v[std::size_t(c)] <= hi + 1e-5f);
      }
    }
  // Constant beyond the ends, and the table spans the axis.
  CHECK(tf->evaluate(-5000)[3] == pts.front().rgba[3]);
  CHECK(tf->evaluate(1e6)[3] == pts.back().rgba[3]);
  const auto table = tf->sample(64);
  CHECK(table.size() == 64);
  CHECK(table.back()[3] == doctest::Approx(pts.back().rgba[3]));
}

TEST_CASE("TransferFunction1D rejects unsorted points and out-of-range channels by index") {
  auto unsorted = TransferFunction1D::fromPoints({{0, {0, 0, 0, 0}}, {0, {1, 1, 1, 1}}});
  REQUIRE_FALSE(unsorted);
  CHECK(unsorted.error().message.find("point 1") != std::string::npos);
  auto bad = TransferFunction1D::fromPoints({{0, {0, 0, 0, 1.5f}}});
  REQUIRE_FALSE(bad);
  CHECK(bad.error().message.find("0..1") != std::string::npos);
}

TEST_CASE("The 2-D table's bilinear lookup returns the entries at texel positions and blends between them") {
  const std::vector<Rgba> data{{0, 0, 0, 0}, {0, 0, 0, 1}};
  const std::vector<Rgba> dist{{0, 0, 0, 1}, {0, 0, 0, 1}};
  const TransferFunction2D tf = buildTransferFunction2D(data, dist, 1.0f, 0, 100);
  CHECK(tf.lookup(0, 0.3)[3] == doctest::Approx(0.0));
  CHECK(tf.lookup(100, 0.3)[3] == doctest::Approx(1.0));
  CHECK(tf.lookup(25, 0.3)[3] == doctest::Approx(0.25));
}
