#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include "render/preset.h"
#include "render/tf_edit.h"
#include "test_support.h"

using namespace at;
using namespace at::render;

namespace {
bool strictlyIncreasing(const std::vector<TfPoint>& p, double gap) {
  for (std::size_t i = 1; i < p.size(); ++i)
    if (!(p[i].x - p[i - 1].x >= gap)) return false;
  return true;
}
}  // namespace

TEST_CASE("TfEdit_AddPoint_InsertsInOrderAndClampsXAndColour") {
  std::vector<TfPoint> pts = Preset{}.dataTf;
  auto i = addTfPoint(pts, 300, {1.5f, -0.2f, 0.5f, 0.5f}, dataAxisRange());
  REQUIRE(i.has_value());
  CHECK(*i == 3);  // after -1000, -100, 60
  CHECK(pts[*i].x == 300);
  CHECK(pts[*i].rgba == Rgba{1, 0, 0.5f, 0.5f});
  auto far = addTfPoint(pts, 1e9, {0, 0, 0, 1}, dataAxisRange());
  REQUIRE(far.has_value());
  CHECK(pts.back().x == 32767);
  CHECK(strictlyIncreasing(pts, 1));
}

TEST_CASE("TfEdit_AddPoint_TooCloseToAnExistingPoint_IsRefusedAndLeavesPointsUnchanged") {
  std::vector<TfPoint> pts = Preset{}.distanceTf;
  const auto before = pts;
  auto r = addTfPoint(pts, 0.5004, {1, 1, 1, 1}, distanceAxisRange());
  CHECK_FALSE(r.has_value());
  CHECK(pts == before);
}

TEST_CASE("TfEdit_MovePoint_StaysBetweenItsNeighboursAndClampsAlpha") {
  std::vector<TfPoint> pts = Preset{}.dataTf;  // -1000, -100, 60, 400, 2000
  auto x = moveTfPoint(pts, 2, 5000, 2.0f, dataAxisRange());
  REQUIRE(x.has_value());
  CHECK(*x == 399);
  CHECK(pts[2].rgba[3] == 1.0f);
  auto first = moveTfPoint(pts, 0, -40000, -1.0f, dataAxisRange());
  REQUIRE(first.has_value());
  CHECK(*first == -32768);
  CHECK(pts[0].rgba[3] == 0.0f);
  CHECK_FALSE(moveTfPoint(pts, 9, 0, 0, dataAxisRange()).has_value());
}

TEST_CASE("TfEdit_RandomEdits_AlwaysLeaveAValidTransferFunctionAndPreset") {
  const auto seed = test::freshSeed("TfEdit_RandomEdits");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-0.2, 1.2);
  std::uniform_int_distribution<int> op(0, 3);
  Preset p;
  for (int n = 0; n < 2000; ++n) {
    const bool data = n % 2 == 0;
    auto& pts = data ? p.dataTf : p.distanceTf;
    const TfAxisRange r = data ? dataAxisRange() : distanceAxisRange();
    const double span = data ? 4000.0 : 1.0, lo = data ? -1500.0 : 0.0;
    const std::size_t idx = std::size_t(std::uniform_int_distribution<int>(0, int(pts.size()) - 1)(rng));
    const Rgba c{float(u(rng)), float(u(rng)), float(u(rng)), float(u(rng))};
    switch (op(rng)) {
      case 0: (void)addTfPoint(pts, lo + u(rng) * span, c, r); break;
      case 1: (void)moveTfPoint(pts, idx, lo + u(rng) * span, float(u(rng)), r); break;
      case 2: (void)deleteTfPoint(pts, idx); break;
      default: REQUIRE(setTfPointColour(pts, idx, c).has_value());
    }
    REQUIRE(pts.size() >= 2);
    REQUIRE(strictlyIncreasing(pts, r.minGap * 0.999));
    REQUIRE(TransferFunction1D::fromPoints(pts).has_value());
  }
  auto back = parsePreset(presetToJson(p), "edited");
  REQUIRE_MESSAGE(back.has_value(), back.error().message);
  CHECK(back->dataTf.size() == p.dataTf.size());
  CHECK(back->distanceTf.size() == p.distanceTf.size());
}

TEST_CASE("TfEdit_DeletePoint_KeepsAtLeastTwoPoints") {
  std::vector<TfPoint> pts{{0, {0, 0, 0, 0}}, {0.5, {1, 1, 1, 1}}, {1, {1, 0, 0, 1}}};
  REQUIRE(deleteTfPoint(pts, 1).has_value());
  CHECK(pts.size() == 2);
  CHECK(pts[1].x == 1);
  CHECK_FALSE(deleteTfPoint(pts, 0).has_value());
  CHECK(pts.size() == 2);
  CHECK_FALSE(setTfPointColour(pts, 2, {0, 0, 0, 0}).has_value());
}

TEST_CASE("TfEdit_HitTest_FindsTheNearestPointWithinTheTolerance") {
  const std::vector<TfPoint> pts{{0, {0, 0, 0, 0}}, {100, {0, 0, 0, 0.5f}}, {110, {0, 0, 0, 0.6f}}};
  CHECK(hitTestTfPoint(pts, 104, 0.5f, 10, 0.1) == std::optional<std::size_t>(1));
  CHECK(hitTestTfPoint(pts, 108, 0.6f, 10, 0.1) == std::optional<std::size_t>(2));
  CHECK_FALSE(hitTestTfPoint(pts, 50, 0.5f, 10, 0.1).has_value());
  CHECK_FALSE(hitTestTfPoint(pts, 100, 0.9f, 10, 0.1).has_value());  // right x, far opacity
}

TEST_CASE("TfEdit_LogHistogram_IsOneAtTheFullestBinAndLogScaled") {
  std::vector<std::int16_t> hu;
  for (int i = 0; i < 999; ++i) hu.push_back(-1000);  // bin 0: 999 values
  for (int i = 0; i < 9; ++i) hu.push_back(100);      // bin 2: 9 values
  hu.push_back(5000);                                 // outside: ignored
  auto h = logHistogram(hu, 4, -1000, 1000);
  REQUIRE(h.size() == 4);
  CHECK(h[0] == doctest::Approx(1.0));
  CHECK(h[1] == 0.0f);
  CHECK(h[2] == doctest::Approx(std::log(10.0) / std::log(1000.0)));
  CHECK(h[3] == 0.0f);
  CHECK(logHistogram({}, 3, 0, 1) == std::vector<float>{0, 0, 0});
}
