// Fuzzy's unit and lighting's reach judged on the picture (render/picture_scale.h), and the composite it is judged
// on (render_settings.h, compositePixel), on the µCT-like phantom (uint8 plain intensities at 0.2 mm)
// without a GPU.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "render/derived_preset.h"
#include "render/picture_scale.h"
#include "render/gradient_volume.h"
#include "render/scene.h"
#include "test_support.h"
#include "volume/mask.h"
#include "volume/structure.h"
#include "wdt/wdt.h"

using namespace at;
using namespace at::render;

namespace {

// The phantom as a µCT would store it: plain uint8 intensities (−1000 … 2000 HU → 0 … 255).
struct MicroCt {
  Dataset ds;
  IntensityLevels levels;
  GradientVolume gradients;
};
const MicroCt& microCt() {
  static const MicroCt ct = [] {
    MicroCt m;
    m.ds = test::phantomOfSize(128);
    for (auto& v : m.ds.volume.voxels) v = std::int16_t(std::clamp(std::lround((v + 1000.0) * 255.0 / 3000.0), 0L, 255L));
    m.ds.volume.geometry.spacingMm = {0.2, 0.2, 0.2};
    m.ds.labels.geometry = m.ds.volume.geometry;
    m.levels = summariseIntensities(m.ds.volume);
    m.gradients = computeGradientVolume(m.ds.volume);
    return m;
  }();
  return ct;
}

struct Framed {
  FloatVolume field;
  RenderSettings settings;
  FieldScale scale;
  SelectedMask mask;
  std::uint16_t selected = 0;
};

// What the ray caster samples for a framed view (pointing into `f`: made where it is used, so that
// moving a Framed leaves nothing dangling).
SceneVolumes sceneOf(const Framed& f) {
  SceneVolumes scene;
  scene.volume = &microCt().ds.volume;
  scene.labels = &microCt().ds.labels;
  scene.field = &f.field;
  scene.selected = f.selected;
  scene.gradients = &microCt().gradients;
  scene.selectedMask = &f.mask;
  return scene;
}

// `id` framed from `view` at 160 px in `mode`, its unit set as the front ends set it (with the
// picture's inputs, or without them).
Framed framed(const std::string& id, const std::string& view, RenderMode mode, bool withPicture) {
  const MicroCt& ct = microCt();
  const Structure* s = ct.ds.findStructure(id);
  REQUIRE(s);
  const Preset preset = derivedPreset(ct.levels, mode, id);
  auto frame = structureFrame(ct.ds.labels, s->label);
  REQUIRE(frame);
  auto params = wdtParamsFor(preset, 2);
  REQUIRE(params);
  params->backend = WdtBackend::Cpu;
  auto wdt = computeWdt(ct.ds.volume, structureMask(ct.ds.labels, s->label), *params);
  REQUIRE(wdt);
  ViewRequest request;
  request.width = request.height = 160;
  request.view = view;
  auto settings = settingsFor(preset, *frame, request);
  REQUIRE(settings);
  Framed f{std::move(wdt->field.distances), *settings, {}, {}, 0};
  const PictureInputs picture{&ct.ds.labels, s->label, &ct.gradients};
  f.scale = applyFieldScale(f.settings, f.field, ct.ds.volume, nullptr, *frame, request, withPicture ? &picture : nullptr);
  f.mask = selectedMask(ct.ds.labels, s->label);
  f.selected = s->label;
  return f;
}

PictureColourShares sharesAtPictureT(const Framed& f) {
  RenderSettings s = f.settings;
  s.preset.t = pictureT(s.preset.mode);
  return pictureColourShares(sceneOf(f), s);
}

double score(const PictureColourShares& s) { return s.near - kFarColourPenalty * s.far; }
// Whether the kept scale colours the far bone enough to be shrunk (and to lose its margin).
bool coloursFar(const PictureColourShares& kept) { return kept.farRays >= kMinPictureRays && kept.far > kFarColourToShrink; }
// The least score a candidate taken over the kept scale has.
double scoreToBeat(const PictureColourShares& kept) { return score(kept) + (coloursFar(kept) ? 0.0 : kPictureMargin) - 1e-9; }
bool isShrink(double factor) { return std::find(kPictureShrinks.begin(), kPictureShrinks.end(), factor) != kPictureShrinks.end(); }

// A view framed without the picture's inputs and with them, and each one's shares at pictureT.
struct KeptAndJudged {
  Framed kept, judged;
  PictureColourShares keptShares, judgedShares;
};
KeptAndJudged keptAndJudged(const std::string& id, const std::string& view, RenderMode mode) {
  KeptAndJudged out{framed(id, view, mode, false), framed(id, view, mode, true), {}, {}};
  out.keptShares = sharesAtPictureT(out.kept);
  out.judgedShares = sharesAtPictureT(out.judged);
  return out;
}

// Structures inside the petrous block, one on its surface (the temporal line), from several sides.
const std::vector<std::pair<std::string, std::string>> kViews = {
    {"cochlea", "superior"},       {"cochlea", "lateral_left"},  {"facial_nerve", "superior"},
    {"lateral_semicircular_canal", "superior"}, {"malleus", "lateral_right"}, {"temporal_line", "lateral_left"}};

}  // namespace

TEST_CASE("compositePixel: the opacity the picker accumulates, the structure's part of it, colours within it") {
  for (RenderMode mode : {RenderMode::Wdt, RenderMode::Fuzzy, RenderMode::Lighting}) {
    CAPTURE(toString(mode));
    const Framed f = framed("cochlea", "superior", mode, false);
    const TransferFunction2D table = shadingTable(f.settings.preset);
    std::size_t drawn = 0;
    for (int y = 2; y < 160; y += 9)
      for (int x = 3; x < 160; x += 9) {
        const CompositedPixel p = compositePixel(sceneOf(f), f.settings, table, x, y);
        const double context = contextOpacity(sceneOf(f), f.settings, table, x, y);
        CHECK(p.alpha == doctest::Approx(context + p.structureAlpha).epsilon(1e-9));
        CHECK(p.alpha <= 1.0);
        CHECK(p.structureAlpha >= 0.0);
        for (double c : p.rgb) {
          CHECK(c >= 0.0);
          CHECK(c <= p.alpha + 1e-9);  // premultiplied: no colour without opacity
        }
        drawn += p.alpha >= 0.1;
      }
    CHECK(drawn > 20);
  }
}

TEST_CASE("pictureColourShares: in colour where all the bone lies at distance 0, nowhere where all of it lies far") {
  Framed f = framed("cochlea", "lateral_left", RenderMode::Fuzzy, false);
  f.settings.preset.t = pictureT(RenderMode::Fuzzy);
  f.settings.distanceOffset = 0;
  f.settings.distanceUnit = 1e9;  // every D at x ≈ 0: the full colour (Eqs. 4–5, weight 1)
  const PictureColourShares all = pictureColourShares(sceneOf(f), f.settings);
  CHECK(all.nearRays >= kMinPictureRays);
  CHECK(all.farRays >= kMinPictureRays);
  CHECK(all.near >= 0.9);
  CHECK(all.far >= 0.9);
  f.settings.distanceUnit = 1e-9;  // every D far: weight 0, the bone in its own colour
  const PictureColourShares none = pictureColourShares(sceneOf(f), f.settings);
  CHECK(none.near <= 0.02);  // (the structure's own rim, where its surface adds under half the opacity)
  CHECK(none.far == 0.0);
}

TEST_CASE("scaleFromPicture: fuzzy inside solid bone the colour reaches the bone next to the structure, never the far bone") {
  // The cochlea from above lies under the petrous block's shell: the first bone each ray meets is
  // the shell, as far in D next to the cochlea as far from it, so the neighbours' unit leaves the
  // bone around it nearly uncoloured. The picture takes a unit from the bone around it.
  const Framed before = framed("cochlea", "superior", RenderMode::Fuzzy, false);
  const Framed after = framed("cochlea", "superior", RenderMode::Fuzzy, true);
  const PictureColourShares b = sharesAtPictureT(before), a = sharesAtPictureT(after);
  MESSAGE("cochlea from above: unit " << before.settings.distanceUnit << " → " << after.settings.distanceUnit
          << "; colour on " << 100 * b.near << " % → " << 100 * a.near << " % of the context next to it, " << 100 * b.far
          << " % → " << 100 * a.far << " % far from it");
  CHECK(after.scale.fromPicture);
  CHECK(a.near >= b.near + 0.2);
  CHECK(a.far <= kMaxFarColour);

  // Every view: the unit taken is the kept one, or one that scores clearly better with at most
  // kMaxFarColour of the far bone in colour; the shares reported are the picture's.
  for (const auto& [id, view] : kViews) {
    CAPTURE(id);
    CAPTURE(view);
    const auto [kept, chosen, k, c] = keptAndJudged(id, view, RenderMode::Fuzzy);
    CHECK(chosen.scale.pictureNear == doctest::Approx(c.near));
    CHECK(chosen.scale.pictureFar == doctest::Approx(c.far));
    if (chosen.scale.fromPicture) {
      if (chosen.scale.pictureShrink != 1) {  // the kept unit, shrunk: only where it coloured the far bone
        CHECK(coloursFar(k));
        CHECK(isShrink(chosen.scale.pictureShrink));
        CHECK(chosen.settings.distanceUnit == doctest::Approx(kept.settings.distanceUnit * chosen.scale.pictureShrink));
        CHECK(chosen.settings.distanceOffset == kept.settings.distanceOffset);
      } else {
        CHECK(chosen.settings.distanceOffset == 0);
        CHECK(chosen.settings.distanceUnit == doctest::Approx(chosen.scale.aroundQuantileD / chosen.scale.pictureAroundX));
      }
      CHECK(c.far <= kMaxFarColour);
      CHECK(score(c) > scoreToBeat(k));
    } else {
      CHECK(chosen.settings.distanceUnit == kept.settings.distanceUnit);
      CHECK(chosen.settings.distanceOffset == kept.settings.distanceOffset);
    }
    // Other modes take nothing from the picture.
    const Framed wdt = framed(id, view, RenderMode::Wdt, true);
    CHECK_FALSE(wdt.scale.fromPicture);
  }
}

TEST_CASE("scaleFromPicture: lighting keeps the distance TF's unit and lights farther only where that keeps the far bone unlit") {
  // Eq. 6's k_a falls to 0.2 at x = 0.7: inside solid bone the bone around the structure lies
  // beyond that, behind the shell, and stays dark. A longer reach lights it where the picture shows
  // that the light stays next to the structure.
  std::size_t chosen = 0;
  for (const auto& [id, view] : kViews) {
    CAPTURE(id);
    CAPTURE(view);
    const auto [kept, judged, k, j] = keptAndJudged(id, view, RenderMode::Lighting);
    MESSAGE(id << " " << view << ": reach " << judged.settings.lightingReach << "; light on " << 100 * k.near << " % → "
                << 100 * j.near << " % of the context next to it, " << 100 * k.far << " % → " << 100 * j.far << " % far from it");
    CHECK(judged.scale.pictureJudged);
    CHECK(judged.settings.distanceUnit == kept.settings.distanceUnit);  // what the distance TF draws is unchanged
    CHECK(judged.settings.distanceOffset == kept.settings.distanceOffset);
    CHECK(judged.scale.pictureNear == doctest::Approx(j.near));
    if (judged.scale.fromPicture) {
      ++chosen;
      const bool longer = std::find(kLightingReaches.begin(), kLightingReaches.end(), judged.settings.lightingReach) !=
                          kLightingReaches.end();
      CHECK((longer || (coloursFar(k) && isShrink(judged.settings.lightingReach))));
      CHECK(j.far <= kMaxFarColour);
      CHECK(score(j) > scoreToBeat(k));
    } else {
      CHECK(judged.settings.lightingReach == 1.0);
    }
  }
  CHECK(chosen >= 1);
}

TEST_CASE("scaleFromPicture: a unit or reach that colours the far bone gives way to one that keeps the far bone clear") {
  // A scale that puts the mode's colour on more than kFarColourToShrink of the far bone (here the
  // unit or the reach stretched 2.5 × beyond what applyFieldScale took) gives way to the
  // best-scoring candidate that keeps the far bone clear: the scale shrunk (kPictureShrinks) or
  // another candidate. Where nothing separates the near bone from the far at these scales (the
  // phantom's malleus from the side), that can leave little colour next to the structure too: the
  // score prefers that to colour on the far bone.
  std::size_t shrunk = 0;
  for (const auto& [id, view] : kViews)
    for (RenderMode mode : {RenderMode::Fuzzy, RenderMode::Lighting}) {
      CAPTURE(id);
      CAPTURE(view);
      CAPTURE(std::string(toString(mode)));
      Framed f = framed(id, view, mode, false);
      FieldScale stretched = f.scale;
      stretched.pictureJudged = stretched.fromPicture = false;
      if (mode == RenderMode::Fuzzy)
        stretched.distanceUnit = f.settings.distanceUnit * 2.5;  // (the request's context scale is 1)
      else
        stretched.lightingReach = 2.5;
      f.settings.distanceUnit = stretched.distanceUnit;
      f.settings.lightingReach = stretched.lightingReach;
      const PictureColourShares before = sharesAtPictureT(f);
      if (!coloursFar(before)) continue;  // nothing to shrink in this view
      FieldScale judged = stretched;
      scaleFromPicture(judged, sceneOf(f), f.settings);
      CHECK(judged.pictureJudged);
      if (!judged.fromPicture) {
        // No candidate that keeps the far bone clear scores better.
        CHECK(judged.distanceUnit == stretched.distanceUnit);
        continue;
      }
      ++shrunk;
      Framed after = f;
      after.settings.distanceUnit = judged.distanceUnit;
      after.settings.distanceOffset = judged.distanceOffset;
      after.settings.lightingReach = judged.lightingReach;
      const PictureColourShares a = sharesAtPictureT(after);
      MESSAGE(id << " " << view << " " << std::string(toString(mode)) << ": in colour " << 100 * before.near << " % → " << 100 * a.near
                 << " % next to it, " << 100 * before.far << " % → " << 100 * a.far << " % far from it (shrink "
                 << judged.pictureShrink << ")");
      CHECK(judged.pictureNear == doctest::Approx(a.near));
      CHECK(judged.pictureFar == doctest::Approx(a.far));
      CHECK(a.far <= kMaxFarColour);
      CHECK(score(a) > score(before));
      if (judged.pictureShrink != 1) {
        CHECK(isShrink(judged.pictureShrink));
        if (mode == RenderMode::Fuzzy)
          CHECK(judged.distanceUnit == doctest::Approx(stretched.distanceUnit * judged.pictureShrink));
        else
          CHECK(judged.lightingReach == doctest::Approx(2.5 * judged.pictureShrink));
      }
      if (mode == RenderMode::Lighting) CHECK(judged.distanceUnit == stretched.distanceUnit);
    }
  CHECK(shrunk >= 2);
}

TEST_CASE("scaleFromPicture: an outline band hidden next to the structure moves out to the bone the view shows, never onto the far bone") {
  // The band lies at one weighted distance; where the bone the view shows next to the structure is
  // all farther than that (its shell runs inside the bone or within the structure's halo), the
  // kept unit draws no band. Here every view's unit is squeezed to 0.3 × what applyFieldScale took,
  // which pulls the band into the structure's rim. Where the squeezed band shows on under
  // kOutlineBandShows of the rays next to the structure, the picture stretches the unit
  // (kOutlineStretches) to the stretch whose band shows there without covering that bone
  // (≤ kOutlineBandMost), keeps the far bone clear (≤ kMaxFarColour) and scores best; where the band
  // shows, the unit stays.
  std::size_t stretched = 0, kept = 0;
  for (const auto& [id, view] : kViews)
    for (double squeeze : {1.0, 0.3}) {
      CAPTURE(id);
      CAPTURE(view);
      CAPTURE(squeeze);
      Framed f = framed(id, view, RenderMode::Outline, false);
      FieldScale start = f.scale;
      start.pictureJudged = start.fromPicture = false;
      start.distanceUnit = f.settings.distanceUnit * squeeze;  // (the request's context scale is 1)
      f.settings.distanceUnit = start.distanceUnit;
      const PictureColourShares before = sharesAtPictureT(f);
      FieldScale judged = start;
      scaleFromPicture(judged, sceneOf(f), f.settings);
      CHECK(judged.pictureJudged);
      CHECK(judged.distanceOffset == start.distanceOffset);
      if (before.nearRays < kMinPictureRays || before.near >= kOutlineBandShows || !judged.fromPicture) {
        CHECK(judged.distanceUnit == start.distanceUnit);
        CHECK(judged.pictureStretch == 1.0);
        kept += before.near >= kOutlineBandShows;
        continue;
      }
      ++stretched;
      CHECK(std::find(kOutlineStretches.begin(), kOutlineStretches.end(), judged.pictureStretch) != kOutlineStretches.end());
      CHECK(judged.distanceUnit == doctest::Approx(start.distanceUnit * judged.pictureStretch));
      Framed after = f;
      after.settings.distanceUnit = judged.distanceUnit;
      const PictureColourShares a = sharesAtPictureT(after);
      MESSAGE(id << " " << view << " × " << squeeze << ": band on " << 100 * before.near << " % → " << 100 * a.near
                 << " % of the bone next to it, " << 100 * before.far << " % → " << 100 * a.far << " % far from it (stretch "
                 << judged.pictureStretch << ")");
      CHECK(judged.pictureNear == doctest::Approx(a.near));
      CHECK(a.near >= kOutlineBandShows);
      CHECK(a.near <= kOutlineBandMost);
      CHECK(a.far <= kMaxFarColour);
      CHECK(score(a) > score(before) + kOutlineStretchMargin);
    }
  CHECK(stretched >= 2);
  CHECK(kept >= 2);
}
