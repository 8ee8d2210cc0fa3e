// A locate key (`class keys`, `class open-exam`) tries only the pixels render::pixelsThatCanPick
// leaves, not every pixel of the picture. Compared here with the full check on random scenes (seed
// printed): every pixel of the picture picked as the terminal picks (render::pickStructure, the
// label under the hit, the target field's distance at the hit's nearest voxel) and graded by the
// laptop's own grader (quiz::gradeLocate). Every pixel the full check counts right lies inside the
// box, so the accepted runs of both are the same. The key's picks read the selected structure's
// smoothed mask worked out once (render::SelectedMask): they equal the picks that smooth it per
// sample, bit for bit.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "quiz/grading.h"
#include "render/camera.h"
#include "render/pick_bounds.h"
#include "render/render_settings.h"
#include "render/structure_pick.h"
#include "test_support.h"

using namespace at;

namespace {

struct Ball {
  Vec3 centre;
  double radius;
};

// A random scene: soft tissue with labelled balls (labels 1..4; air-filled ones are hollow, as
// canals are) and, unless `clear`, unlabelled bone balls that hide what is behind them; the
// target's distance field on its own grid (the labels' grid or a coarser, shifted one), the
// Euclidean distance to the target ball times a random factor, with unknown (negative, infinite)
// distances here and there.
struct RandomScene {
  Volume volume;
  LabelMap labels;
  FloatVolume field;
  std::uint16_t target = 1;
  Ball targetBall{};
  RandomScene(std::mt19937_64& random, bool clear) {
    std::uniform_real_distribution<double> unit(0, 1);
    Geometry g;
    g.dims = {24 + int(random() % 17), 24 + int(random() % 17), 24 + int(random() % 17)};
    g.spacingMm = {0.3 + 0.5 * unit(random), 0.3 + 0.5 * unit(random), 0.3 + 0.5 * unit(random)};
    g.originMm = {-0.5 * g.dims.x * g.spacingMm[0], -0.5 * g.dims.y * g.spacingMm[1], -0.5 * g.dims.z * g.spacingMm[2]};
    volume = Volume(g, std::int16_t(random() % 2 ? 40 : -1000));
    labels = LabelMap(g, 0);
    const Vec3 half = {0.5 * g.dims.x * g.spacingMm[0], 0.5 * g.dims.y * g.spacingMm[1], 0.5 * g.dims.z * g.spacingMm[2]};
    const auto randomBall = [&](double maxRadius) {
      return Ball{{(unit(random) - 0.5) * 1.4 * half[0], (unit(random) - 0.5) * 1.4 * half[1], (unit(random) - 0.5) * 1.4 * half[2]},
                  0.6 + unit(random) * maxRadius};
    };
    const auto paint = [&](const Ball& b, std::int16_t hu, std::uint16_t label) {
      for (int k = 0; k < g.dims.z; ++k)
        for (int j = 0; j < g.dims.y; ++j)
          for (int i = 0; i < g.dims.x; ++i)
            if (norm(g.indexToPatient({double(i), double(j), double(k)}) - b.centre) <= b.radius) {
              volume.at(i, j, k) = hu;
              labels.at(i, j, k) = label;
            }
    };
    const int balls = 1 + int(random() % 4);
    for (std::uint16_t l = 1; l <= balls; ++l) {
      const Ball b = randomBall(3.0);
      const std::int16_t hu = random() % 3 == 0 ? -1000 : std::int16_t(random() % 2 ? 300 : 1200);
      paint(b, hu, l);
      if (l == 1) targetBall = b;
    }
    if (!clear)
      for (int n = int(random() % 4); n > 0; --n) paint(randomBall(2.5), 1500, 0);
    // A later ball may have painted over part of the target: it is whatever keeps label 1.
    Geometry fg = g;
    if (random() % 2) {
      fg.dims = {g.dims.x / 2 + 1, g.dims.y / 2 + 1, g.dims.z / 2 + 1};
      fg.spacingMm = {2 * g.spacingMm[0], 2 * g.spacingMm[1], 2 * g.spacingMm[2]};
      fg.originMm = {g.originMm[0] + 0.3 * unit(random), g.originMm[1], g.originMm[2] - 0.3 * unit(random)};
    }
    field = FloatVolume(fg, 0);
    const double factor = 0.5 + 1.5 * unit(random);
    for (int k = 0; k < fg.dims.z; ++k)
      for (int j = 0; j < fg.dims.y; ++j)
        for (int i = 0; i < fg.dims.x; ++i) {
          const double d = std::max(0.0, norm(fg.indexToPatient({double(i), double(j), double(k)}) - targetBall.centre) - targetBall.radius);
          const int odd = int(random() % 50);
          field.at(i, j, k) = odd == 0 ? -1.0f : odd == 1 ? std::numeric_limits<float>::infinity() : float(factor * d);
        }
  }
};

// As TerminalViews::pickAt names a click: the structure of the label under it ("s<label>"), the
// field's distance at its nearest voxel (unknown off the field's grid or without a hit).
quiz::Pick pickOf(const render::PickResult& hit, const FloatVolume& field) {
  quiz::Pick pick;
  if (!hit.hit) return pick;
  if (hit.label != 0) pick.structure = "s" + std::to_string(hit.label);
  const Vec3 ijk = field.geometry.patientToIndex(hit.pointMm);
  const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
  if (field.geometry.dims.contains(i, j, k)) pick.distanceMm = field.at(i, j, k);
  return pick;
}

}  // namespace

TEST_CASE("LocateKeyPixels_EveryPixelTheGraderCountsRightLiesWhereTheKeyLooks_RandomScenes") {
  const std::uint64_t seed = test::freshSeed("LocateKeyPixels_EveryPixelTheGraderCountsRight");
  INFO("seed " << seed);
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  const char* sides[] = {"anterior", "posterior", "lateral_left", "lateral_right", "superior", "inferior"};
  const double tolerances[] = {0, 0, 0.3, 1.0, 2.5};
  const quiz::GradingContext context;
  long pixels = 0, skipped = 0, right = 0, rightByDistance = 0, scenesWithRight = 0, maskDiffers = 0;
  const int scenes = 40;
  for (int n = 0; n < scenes; ++n) {
    RandomScene scene(random, n % 3 == 0);
    render::RenderSettings s;
    s.width = 24 + int(random() % 49);
    s.height = 24 + int(random() % 41);
    s.opacityRefMm = 0.25;
    // Looking at the target (or near it) from a named side, then turned a little, from near or far.
    const Vec3 aim = scene.targetBall.centre + 2.0 * Vec3{unit(random) - 0.5, unit(random) - 0.5, unit(random) - 0.5};
    s.camera = render::Camera::named(*render::parseNamedView(sides[random() % 6]), aim, 6 + 10 * unit(random));
    s.camera.orbit(40 * (unit(random) - 0.5), 40 * (unit(random) - 0.5));
    s.camera.orthographic = random() % 4 == 0;
    if (random() % 3 == 0) {
      auto clip = render::ClipPlane::fromCoefficients(unit(random) - 0.5, unit(random) - 0.5, unit(random) - 0.5,
                                                      2 * (unit(random) - 0.5));
      if (clip) s.clip = *clip;
    }
    const double tolerance = n % 4 == 1 ? 2.5 : tolerances[random() % 5];  // every kind, often
    quiz::ResolvedQuestion question;
    question.question.id = "random.locate";
    question.question.kind = quiz::QuestionKind::Locate;
    question.question.target = "s1";
    question.question.toleranceMm = tolerance;

    const render::SceneVolumes volumes{&scene.volume, &scene.labels, &scene.field, 1};
    // The picks with the selected structure's mask worked out once (as the terminal's key does)
    // must equal these, bit for bit.
    const render::SelectedMask mask = render::selectedMask(scene.labels, 1);
    render::SceneVolumes withMask = volumes;
    withMask.selectedMask = &mask;
    const render::TransferFunction2D table = render::shadingTable(s.preset);
    const auto box = render::pixelsThatCanPick(scene.labels, 1, tolerance > 0 ? &scene.field : nullptr, tolerance, s);
    const auto inBox = [&](int x, int y) {
      return !box || (x >= (*box)[0] && x <= (*box)[2] && y >= (*box)[1] && y <= (*box)[3]);
    };
    long rightHere = 0;
    for (int y = 0; y < s.height; ++y)
      for (int x = 0; x < s.width; ++x) {
        const render::PickResult hit = render::pickStructure(volumes, s, table, x, y);
        const render::PickResult fast = render::pickStructure(withMask, s, table, x, y);
        if (fast.hit != hit.hit || fast.label != hit.label || fast.pointMm != hit.pointMm ||
            fast.accumulatedOpacity != hit.accumulatedOpacity)
          ++maskDiffers;
        const quiz::Pick pick = pickOf(hit, scene.field);
        auto grade = quiz::gradeLocate(question, pick, context);
        REQUIRE(grade);
        ++pixels;
        if (!inBox(x, y)) ++skipped;
        if (!grade->correct) continue;
        ++rightHere;
        if (pick.structure != "s1") ++rightByDistance;
        CAPTURE(n);
        CAPTURE(x);
        CAPTURE(y);
        CAPTURE(tolerance);
        CHECK(inBox(x, y));  // a right pixel the key would never try
      }
    right += rightHere;
    scenesWithRight += rightHere > 0;
  }
  MESSAGE("seed " << seed << ": " << pixels << " pixels graded, " << right << " right (" << rightByDistance
                  << " by distance) in " << scenesWithRight << " of " << scenes << " scenes; the key skips " << skipped);
  // The comparison must have met right pixels of both kinds and skipped pixels, or it shows little.
  CHECK(maskDiffers == 0);
  CHECK(scenesWithRight >= 3);
  CHECK(right > 50);
  CHECK(skipped > pixels / 10);
}
