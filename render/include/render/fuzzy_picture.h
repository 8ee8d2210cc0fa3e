// Fuzzy mode's (Fig. 5) distance unit, chosen by the colours the framed view's picture shows.
//
// Why: unitFromNeighbours (field_scale.h) sets fuzzy's unit from the first bone surface each ray
// of the view meets. Where the structure lies inside solid bone — the µCT-like phantom's lateral
// canal seen from above — that surface is the outer shell, as far in D next to the structure as
// far from it, and the colour reached 7 % of the context next to the canal. A unit from the bone
// around the structure coloured 41 % there; but on the skull CT the same rule, taken from the data
// alone, coloured more of the far bone than of the near (the sphenoid sinus, the coronoid process),
// because which bone shows depends on what lies in front of what in this view. So the candidates
// are judged on the picture itself, at t = kPictureT, the t fuzzy's presets (shipped and derived)
// open with, whatever the slider's t (so the unit does not change as t moves):
//  - the picture: compositePixel (render_settings.h, the ray caster's classification without its
//    light) on a grid of kPictureRaysPerSide rays along the view's longer side. A ray is in the
//    structure's colour where the composite is drawn (opacity ≥ 0.1, value ≥ 0.15) and has the hue
//    of the distance TF's colour at the structure (n = 1; within 25°, saturation ≥ 0.35). near: the share of the drawn rays within
//    kNeighbourRing of the structure's silhouette (rays where the structure's surface adds ≥ 0.5
//    opacity) that are in colour; far: the same beyond kFarFromStructure. Against the GPU picture
//    (µCT-like phantom, skull CT; 4 units on each of 10 views) its near shares ran up to 33 points
//    higher (the structure's unlit rim), its far shares up to 10; across the units both rose and
//    fell together, which is what the choice needs.
//  - the candidates: the unit unitFromNeighbours set (kept unless another is clearly better), and
//    the around set's median D (FieldScale::aroundQuantileD) placed at x = kPictureAroundX[i],
//    offset 0.
//  - the choice: score = near − kFarColourPenalty × far; a candidate colouring more than
//    kMaxFarColour of the far rays is never taken; another replaces the kept unit only when its
//    score is higher by kPictureMargin.
// Cost: at most 1 + size(kPictureAroundX) pictures of about 40 × 30 rays, each ray marched as the
// ray caster marches, once per field and framed view: `render skull mastoid_air_cells_right` at
// 400 × 300 on 2 cores set the fuzzy unit in 333–372 ms, the lighting unit (the same measures
// without the picture) in 60–79 ms. The desktop measures it on its worker with the rest of the
// unit (app/src/desktop/view/field_unit.h).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "render/field_scale.h"
#include "render/gradient_volume.h"
#include "render/render_settings.h"

namespace at::render {

constexpr int kPictureRaysPerSide = 40;
constexpr float kPictureT = 0.12f;
constexpr std::array<double, 4> kPictureAroundX = {0.9, 1.15, 1.5, 2.0};
constexpr double kFarColourPenalty = 3.0;
constexpr double kMaxFarColour = 0.10;
constexpr double kPictureMargin = 0.10;
// A share counts only over at least this many drawn rays.
constexpr std::size_t kMinPictureRays = 16;

// What the picture is drawn from besides the volume and the field: the label map (on the volume's
// grid), the structure shown and the volume's gradients (null: every edge at full opacity).
struct PictureInputs {
  const LabelMap* labels = nullptr;
  std::uint16_t selected = 0;
  const GradientVolume* gradients = nullptr;
};

// The shares of the drawn rays in the structure's colour next to it and far from it (see above),
// for `settings` as they are (their unit, offset and t); counts of the drawn rays in each set.
struct FuzzyColourShares {
  double near = 0, far = 0;
  std::size_t nearRays = 0, farRays = 0;
};
FuzzyColourShares fuzzyColourShares(const SceneVolumes& scene, const RenderSettings& settings);

// Chooses fuzzy's unit by the picture (see above) for `settings`' view and preset; `scale` holds the
// unit unitFromNeighbours set and the around set's median. `contextScale` multiplies every
// candidate unit as applyFieldScale applies it. Sets scale's unit (offset 0 when an around
// candidate wins), pictureNear/pictureFar (the taken unit's shares), pictureJudged, fromPicture
// and pictureAroundX. Does nothing for a mode other than fuzzy, without labels or a selected structure.
void unitFromFuzzyPicture(FieldScale& scale, const SceneVolumes& scene, const RenderSettings& settings,
                          double contextScale = 1.0);

}  // namespace at::render
