#include "render/picture_scale.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "core/parallel_rows.h"
#include "render/transfer_function.h"
#include "view_rays.h"

namespace at::render {

namespace {

// Hue in degrees (0 … 360), or −1 for a grey.
double hueOf(double r, double g, double b) {
  const double mx = std::max({r, g, b}), mn = std::min({r, g, b});
  if (mx - mn < 1e-9) return -1;
  const double h = mx == r ? (g - b) / (mx - mn) : mx == g ? 2 + (b - r) / (mx - mn) : 4 + (r - g) / (mx - mn);
  return std::fmod(h * 60 + 360, 360);
}

// The colour the mode puts on the bone near the structure: fuzzy's distance TF colour at n = 1
// (distance 0), which Eqs. 4–5 mix into the bone with the TF's opacity as weight; outline's band,
// the distance TF's colour at the band's n; lighting's light, the highlight (Eq. 6).
std::array<double, 3> modeColour(const Preset& preset) {
  if (preset.mode == RenderMode::Fuzzy || preset.mode == RenderMode::Outline)
    if (const auto dist = TransferFunction1D::fromPoints(preset.distanceTf)) {
      const Rgba c = dist->evaluate(preset.mode == RenderMode::Fuzzy ? 1.0 : double(outlineBandN(preset)));
      return {c[0], c[1], c[2]};
    }
  return {preset.highlightRgb[0], preset.highlightRgb[1], preset.highlightRgb[2]};
}

bool inColour(const CompositedPixel& p, double targetHue) {
  const double r = p.rgb[0], g = p.rgb[1], b = p.rgb[2];
  const double mx = std::max({r, g, b}), mn = std::min({r, g, b});
  if (mx <= 0 || (mx - mn) / mx < 0.35) return false;
  const double hue = hueOf(r, g, b);
  if (hue < 0 || targetHue < 0) return false;
  const double gap = std::fabs(hue - targetHue);
  return std::min(gap, 360 - gap) <= 25;
}

// The choice's rules (see the header): the score, 0 over too few rays next to the structure, and
// whether a candidate keeps the far bone clear.
double pictureScore(const PictureColourShares& s) {
  return s.nearRays >= kMinPictureRays ? s.near - kFarColourPenalty * s.far : 0.0;
}
bool keepsFarClear(const PictureColourShares& s) {
  return s.nearRays >= kMinPictureRays && (s.farRays < kMinPictureRays || s.far <= kMaxFarColour);
}

}  // namespace

bool judgedOnPicture(RenderMode mode) {
  return mode == RenderMode::Fuzzy || mode == RenderMode::Lighting || mode == RenderMode::Outline;
}

float pictureT(RenderMode mode) {
  return mode == RenderMode::Lighting ? 0.25f : mode == RenderMode::Outline ? 0.0f : 0.12f;
}

PictureColourShares pictureColourShares(const SceneVolumes& scene, const RenderSettings& settings) {
  PictureColourShares out;
  const auto [w, h] = detail::rayGridOf(settings.width, settings.height, kPictureRaysPerSide);
  if (w < 1 || h < 1 || !scene.volume || !scene.field) return out;
  RenderSettings grid = settings;
  grid.width = w;
  grid.height = h;
  const TransferFunction2D table = shadingTable(grid.preset);
  const auto colour = modeColour(grid.preset);
  const double targetHue = hueOf(colour[0], colour[1], colour[2]);
  std::vector<CompositedPixel> picture(std::size_t(w) * std::size_t(h));
  forEachRowInParallel(h, [&, w = w](int py) {
    for (int px = 0; px < w; ++px) picture[std::size_t(py) * std::size_t(w) + std::size_t(px)] = compositePixel(scene, grid, table, px, py);
  });
  std::vector<char> structure(picture.size(), 0);
  for (std::size_t i = 0; i < picture.size(); ++i) structure[i] = picture[i].structureAlpha >= 0.5;
  const std::vector<int> apart = detail::raysFromStructure(structure, w, h);
  const double side = double(std::max(w, h));
  const double nearRing = grid.preset.mode == RenderMode::Outline ? kOutlineRing : kNeighbourRing;
  std::size_t nearIn = 0, farIn = 0;
  for (std::size_t i = 0; i < picture.size(); ++i) {
    const CompositedPixel& p = picture[i];
    if (structure[i] || p.structureAlpha >= 0.1 || p.alpha < 0.1 || std::max({p.rgb[0], p.rgb[1], p.rgb[2]}) < 0.15) continue;
    const bool in = inColour(p, targetHue);
    if (double(apart[i]) <= nearRing * side) {
      ++out.nearRays;
      nearIn += in;
    } else if (double(apart[i]) >= kFarFromStructure * side) {
      ++out.farRays;
      farIn += in;
    }
  }
  if (out.nearRays) out.near = double(nearIn) / double(out.nearRays);
  if (out.farRays) out.far = double(farIn) / double(out.farRays);
  return out;
}

namespace {

// Outline (see the header): the kept unit unless its band shows on too few rays next to the
// structure; then each stretch in turn replaces the best so far where its band shows without
// covering the bone next to the structure, keeps the far bone clear and scores better by
// kOutlineStretchMargin.
void outlineFromPicture(FieldScale& scale, const std::function<PictureColourShares(double)>& sharesAt) {
  const PictureColourShares kept = sharesAt(scale.distanceUnit);
  scale.pictureNear = kept.near;
  scale.pictureFar = kept.far;
  scale.pictureJudged = true;
  if (kept.nearRays < kMinPictureRays || kept.near >= kOutlineBandShows) return;
  double bestScore = pictureScore(kept), bestStretch = 1;
  PictureColourShares best = kept;
  for (double stretch : kOutlineStretches) {
    const PictureColourShares s = sharesAt(scale.distanceUnit * stretch);
    if (!keepsFarClear(s) || s.near < kOutlineBandShows || s.near > kOutlineBandMost) continue;
    if (pictureScore(s) > bestScore + kOutlineStretchMargin) {
      bestScore = pictureScore(s);
      bestStretch = stretch;
      best = s;
    }
  }
  if (bestStretch == 1) return;
  scale.distanceUnit *= bestStretch;
  scale.pictureStretch = bestStretch;
  scale.pictureNear = best.near;
  scale.pictureFar = best.far;
  scale.fromPicture = true;
  scale.derived = true;
}

}  // namespace

void scaleFromPicture(FieldScale& scale, const SceneVolumes& scene, const RenderSettings& settings, double contextScale) {
  if (!judgedOnPicture(settings.preset.mode) || !scene.labels || scene.selected == 0) return;
  const bool fuzzy = settings.preset.mode == RenderMode::Fuzzy;
  RenderSettings look = settings;
  look.preset.t = pictureT(settings.preset.mode);
  // The structure's smoothed mask once for every picture (marched without it, each sample smooths).
  SceneVolumes withMask = scene;
  SelectedMask mask;
  if (!withMask.selectedMask) {
    mask = selectedMask(*scene.labels, scene.selected);
    withMask.selectedMask = &mask;
  }
  const auto sharesAt = [&](double unit, double offset, double reach) {
    look.distanceUnit = unit * contextScale;
    look.distanceOffset = offset;
    look.lightingReach = reach;
    return pictureColourShares(withMask, look);
  };
  if (settings.preset.mode == RenderMode::Outline) {
    outlineFromPicture(scale, [&](double unit) { return sharesAt(unit, scale.distanceOffset, scale.lightingReach); });
    return;
  }
  const PictureColourShares kept = sharesAt(scale.distanceUnit, scale.distanceOffset, scale.lightingReach);
  scale.pictureNear = kept.near;
  scale.pictureFar = kept.far;
  scale.pictureJudged = true;
  // The kept scale wins by kPictureMargin unless it colours the far bone clearly (then it is also
  // tried shrunk).
  const bool keptColoursFar = kept.farRays >= kMinPictureRays && kept.far > kFarColourToShrink;
  double bestScore = pictureScore(kept) + (keptColoursFar ? 0.0 : kPictureMargin), bestX = 0, bestReach = 0, bestShrink = 1;
  PictureColourShares best = kept;
  if (fuzzy && scale.aroundQuantileD > 0)
    for (double x : kPictureAroundX) {
      const PictureColourShares s = sharesAt(scale.aroundQuantileD / x, 0, 1);
      if (keepsFarClear(s) && pictureScore(s) > bestScore) {
        bestScore = pictureScore(s);
        bestX = x;
        best = s;
      }
    }
  if (keptColoursFar)
    for (double shrink : kPictureShrinks) {
      const PictureColourShares s = fuzzy ? sharesAt(scale.distanceUnit * shrink, scale.distanceOffset, 1)
                                          : sharesAt(scale.distanceUnit, scale.distanceOffset, scale.lightingReach * shrink);
      if (keepsFarClear(s) && pictureScore(s) > bestScore) {
        bestScore = pictureScore(s);
        bestX = 0;
        bestShrink = shrink;
        best = s;
      }
    }
  if (!fuzzy) {
    for (double reach : kLightingReaches) {
      const PictureColourShares s = sharesAt(scale.distanceUnit, scale.distanceOffset, reach);
      if (keepsFarClear(s) && pictureScore(s) > bestScore) {
        bestScore = pictureScore(s);
        bestReach = reach;
        bestShrink = 1;
        best = s;
      }
    }
  }
  if (bestX == 0 && bestReach == 0 && bestShrink == 1) return;
  if (bestX > 0) {
    scale.distanceUnit = scale.aroundQuantileD / bestX;
    scale.distanceOffset = 0;
    scale.pictureAroundX = bestX;
  } else if (bestShrink != 1) {
    if (fuzzy)
      scale.distanceUnit *= bestShrink;
    else
      scale.lightingReach *= bestShrink;
    scale.pictureShrink = bestShrink;
  } else {
    scale.lightingReach = bestReach;
  }
  scale.pictureNear = best.near;
  scale.pictureFar = best.far;
  scale.fromPicture = true;
  scale.derived = true;
}

}  // namespace at::render
