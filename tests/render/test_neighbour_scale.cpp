// The fuzzy and lighting modes' distance unit from the bone the view shows next to the structure
// and far from it (render/field_scale.h, unitFromNeighbours): properties over random measures.
#include <doctest/doctest.h>

#include <cstdio>
#include <random>

#include "render/field_scale.h"
#include "test_support.h"

using namespace at;
using namespace at::render;

namespace {

// x of D under a scale (the presets' distance coordinate).
double xOf(const FieldScale& s, double D) { return std::max(0.0, D - s.distanceOffset) / s.distanceUnit; }

}  // namespace

TEST_CASE("unitFromNeighbours: fuzzy colours the bone next to the structure and leaves the far bone; lighting lights the near bone and leaves the far one dark") {
  const std::uint64_t seed = test::freshSeed("unitFromNeighbours");
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> logD(-2.0, 3.0), ratio(0.5, 6.0), offsetShare(0.0, 0.8), lowShare(0.5, 1.0);
  for (int round = 0; round < 2000; ++round) {
    NeighbourBone bone;
    bone.nearD = std::exp(logD(rng));
    bone.farD = bone.nearD * ratio(rng);
    bone.farLowD = bone.farD * lowShare(rng);
    bone.nearRays = bone.farRays = kMinNeighbourRays + std::size_t(round % 50);
    FieldScale around;
    around.distanceUnit = std::exp(logD(rng)) / kContextQuantileX;
    around.distanceOffset = offsetShare(rng) * around.distanceUnit;
    around.derived = true;
    CAPTURE(bone.nearD);
    CAPTURE(bone.farD);
    CAPTURE(bone.farLowD);
    CAPTURE(around.distanceUnit);
    CAPTURE(around.distanceOffset);
    const bool separated = bone.farD >= kNeighbourSeparates * bone.nearD;
    const bool lightSeparated = bone.farLowD >= kLightSeparates * bone.nearD;
    for (RenderMode mode : {RenderMode::Fuzzy, RenderMode::Lighting}) {
      CAPTURE(toString(mode));
      FieldScale s = around;
      unitFromNeighbours(s, bone, mode);
      REQUIRE(s.distanceUnit > 0);
      CHECK(s.nearRingD == bone.nearD);
      CHECK(s.farRingD == bone.farD);
      // The far bone never lands nearer than kNeighbourFarX (no colour there).
      CHECK(xOf(s, bone.farD) >= kNeighbourFarX * (1 - 1e-9));
      if (mode == RenderMode::Fuzzy && separated) {
        // The near bone at kNeighbourX, unless the far cap shrinks the unit (then nearer x, less colour).
        CHECK(s.fromNeighbours);
        CHECK(s.distanceOffset == 0);
        CHECK(xOf(s, bone.nearD) >= kNeighbourX * (1 - 1e-9));
        if (bone.farD / kNeighbourFarX >= bone.nearD / kNeighbourX) CHECK(xOf(s, bone.nearD) == doctest::Approx(kNeighbourX));
      } else if (mode == RenderMode::Lighting && lightSeparated) {
        // The near bone at kLightNearX (k_a 0.3 of Eq. 6 with the derived α), or nearer where the
        // offset would be negative; the far set's lower quartile exactly at kNeighbourFarX; every D
        // between lands between them, in order.
        CHECK(s.fromNeighbours);
        CHECK(s.distanceOffset >= 0);
        CHECK(xOf(s, bone.nearD) <= kLightNearX * (1 + 1e-9));
        if (s.distanceOffset > 0) CHECK(xOf(s, bone.nearD) == doctest::Approx(kLightNearX));
        CHECK(xOf(s, bone.farLowD) == doctest::Approx(kNeighbourFarX));
        const double mid = 0.5 * (bone.nearD + bone.farLowD);
        CHECK(xOf(s, mid) > xOf(s, bone.nearD));
        CHECK(xOf(s, mid) < xOf(s, bone.farLowD));
      } else {
        // The around unit stays where it leaves the far bone faint; else only shrinks.
        if (xOf(around, bone.farD) >= kNeighbourFarX) {
          CHECK(s.distanceUnit == around.distanceUnit);
          CHECK(s.distanceOffset == around.distanceOffset);
          CHECK_FALSE(s.fromNeighbours);
        } else {
          CHECK(s.fromNeighbours);
          CHECK(s.distanceOffset == 0);
          // every D up to the far bone's lands at an x at least as large as before: the colour
          // only recedes there
          for (double D : {bone.nearD, bone.farD, 0.5 * bone.nearD})
            if (D <= bone.farD) CHECK(xOf(s, D) >= xOf(around, D) - 1e-9 * (1 + xOf(around, D)));
        }
      }
    }
  }
  // Too few rays next to the structure: nothing is measured, the around unit stays (fuzzy).
  FieldScale s;
  s.distanceUnit = 0.7;
  NeighbourBone few;
  few.nearD = 1;
  few.nearRays = kMinNeighbourRays - 1;
  unitFromNeighbours(s, few, RenderMode::Fuzzy);
  CHECK(s.distanceUnit == 0.7);
  CHECK_FALSE(s.fromNeighbours);
}
