// Fuzzy's distance unit (Fig. 5), lighting's reach (Fig. 7) and outline's unit (Fig. 6), judged on
// the colours the framed view's picture shows.
//
// Why: unitFromNeighbours (field_scale.h) sets both from the first bone surface each ray of the
// view meets. Where the structure lies inside solid bone — the µCT-like phantom's lateral canal
// seen from above — that surface is the outer shell, as far in D next to the structure as far
// from it: fuzzy coloured 7.3 % of the context next to the canal and lighting lit 0.6 %. A fuzzy
// unit from the bone around the structure coloured 41 % there; but on the skull CT the same rule,
// taken from the distances alone, coloured more of the far bone than of the near (the sphenoid
// sinus, the coronoid process), because which bone shows depends on what lies in front of what in
// this view. So the candidates are judged on the picture itself, at t = pictureT(mode), the t the
// mode's derived presets open with, whatever the slider's t (the unit does not change as t moves):
//  - the picture: compositePixel (render_settings.h, the ray caster's classification; fuzzy
//    without its light, which changes the brightness and not the hue; lighting with it, since its
//    neutral part sets how saturated the light's colour looks) on a grid of kPictureRaysPerSide
//    rays along the view's longer side. A ray is in the mode's colour (fuzzy: the distance TF's
//    colour at the structure, n = 1; lighting: the light's, the highlight) where the composite is
//    drawn (opacity ≥ 0.1, value ≥ 0.15) and has that hue (within 25°, saturation ≥ 0.35). near:
//    the share of the drawn rays within kNeighbourRing of the structure's silhouette (rays where
//    the structure's surface adds ≥ 0.5 opacity) that are in colour; far: the same beyond
//    kFarFromStructure. Rays where the structure adds 0.1 or more (its rim) count in neither: they
//    show the structure's own colour (with them, the skull's sphenoid sinus in lighting read as
//    100 % lit next to it, where the GPU picture showed 0 %). Against the GPU picture (fuzzy: µCT-like phantom and skull CT, 4 units on
//    each of 10 views) the near shares ran up to 33 points higher (the structure's unlit rim), the
//    far shares up to 10; across the candidates both rose and fell together, which is what the
//    choice needs.
//  - the candidates: fuzzy — the unit unitFromNeighbours set (kept unless another is clearly
//    better), and the around set's median D (FieldScale::aroundQuantileD) placed at x =
//    kPictureAroundX[i], offset 0; lighting — the unit stays (it sets what the distance TF draws),
//    and Eq. 6's k_a takes x = D' / (unit × reach) for reach 1 (kept) or kLightingReaches[i]: a
//    reach above 1 lights bone farther from the structure (RenderSettings::lightingReach).
//    Where the kept scale itself colours more than kFarColourToShrink of the far rays, the kept unit
//    (fuzzy) or reach (lighting) shrunk by kPictureShrinks[i] too: on the skull CT the kept units
//    tinted the face far from the ethmoid cells and the right maxillary sinus seen from the front
//    (26 and 24 % of the far rays), and lighting lit the skull base far from the atlas and the
//    maxilla (22 … 47 %). (From kMaxFarColour on, the shrink took colour from the bone next to
//    the skull's frontal sinus in lighting, 17.2 → 8.6 % in the GPU picture, where the CPU's far
//    share of 10.7 % was 2.2 % in the GPU's.)
//  - the choice: score = near − kFarColourPenalty × far; a candidate colouring more than
//    kMaxFarColour of the far rays is never taken; another replaces the kept one when its score is
//    higher — by kPictureMargin unless the kept one colours more than kFarColourToShrink. Where no
//    unit tells the near bone from the far (the skull's ethmoid cells from the front: GPU picture 55.9 %
//    near, 33.3 % far), the score prefers little colour (5.2 / 2.7 %) to colour on the far bone: a
//    tint far from the structure tells a student that bone is near it.
// Outline: the band lies at one weighted distance (x ≈ 0.58 units) and is drawn where its shell
// meets the bone the view shows. Where that bone next to the structure is all farther in D — one
// 3 mm voxel of bone already spans D 1.2 on the abdominal CT, so around L1 the band's D 1.18 lay in
// the structure's halo; the skull's frontal sinus seen from the front through its anterior wall
// (outer surface at D 1.1–1.5, the band at 0.66) — no band showed. So where the kept unit's band is
// in its colour on under kOutlineBandShows of the drawn rays within kOutlineRing of the structure
// (the neighbouring bone lies a few voxels out, beyond kNeighbourRing; on the skull CT at 160,
// 400 × 300 and 560 × 720 px the bands that read had 12–38 %, the mandible, the temporal line and
// both zygomatic arches, and the hidden or speckled ones at most 4.5 %), the unit is tried × each of
// kOutlineStretches; a stretch replaces the best so far where its band shows there without covering
// that bone (≤ kOutlineBandMost: beyond it the band's shell seen through translucent bone reads as
// a green fog, as on the skull's mastoid cells at × 3.4, 43 %), colours at most kMaxFarColour of
// the far rays and scores better (near − kFarColourPenalty × far) by kOutlineStretchMargin. The
// stretch moves the band and the context's fade together (the fade's unit is the band's); where the
// kept band shows, the unit stays, as measured on the bone around the structure.
// Cost: at most 1 + 4 pictures of about 40 × 30 rays (4 more where the kept scale colours the far
// bone), each ray marched as the ray caster marches, once per field and framed view: `render skull mastoid_air_cells_right` at 400 × 300 on 2 cores
// set the fuzzy unit in 331–372 ms and the lighting unit in 252–271 ms, against 60–79 ms for the
// lighting unit without the picture (bench/RESULTS.md); outline's unit in 65–66 ms where the
// kept band shows (the mandible from the side) and 347–369 ms where all four stretches are tried
// (the frontal sinus from the front). The desktop measures it on its worker with the rest of the unit
// (app/src/desktop/view/field_unit.h).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "render/field_scale.h"
#include "render/gradient_volume.h"
#include "render/render_settings.h"

namespace at::render {

constexpr int kPictureRaysPerSide = 40;
constexpr std::array<double, 4> kPictureAroundX = {0.9, 1.15, 1.5, 2.0};
constexpr std::array<double, 3> kLightingReaches = {1.4, 2.0, 2.8};
constexpr std::array<double, 4> kPictureShrinks = {0.85, 0.75, 0.65, 0.55};
constexpr double kFarColourPenalty = 3.0;
constexpr double kMaxFarColour = 0.10;
constexpr double kFarColourToShrink = 0.15;
constexpr double kPictureMargin = 0.10;
// A share counts only over at least this many drawn rays.
constexpr std::size_t kMinPictureRays = 16;
// Outline: next to the structure means within this share of the grid's longer side (the band lies
// on the neighbouring bone, a few voxels out); the band shows where at least kOutlineBandShows of
// the drawn rays there are in its colour; else the unit is tried stretched by kOutlineStretches.
constexpr double kOutlineRing = 0.12;
constexpr double kOutlineBandShows = 0.06;
constexpr double kOutlineBandMost = 0.30;
constexpr std::array<double, 4> kOutlineStretches = {1.5, 2.0, 2.6, 3.4};
constexpr double kOutlineStretchMargin = 0.05;

// Whether a mode's scale is judged on the picture (fuzzy, lighting and outline), and the t it is
// judged at.
bool judgedOnPicture(RenderMode mode);
float pictureT(RenderMode mode);

// What the picture is drawn from besides the volume and the field: the label map (on the volume's
// grid), the structure shown and the volume's gradients (null: every edge at full opacity, and
// lighting without its key light).
struct PictureInputs {
  const LabelMap* labels = nullptr;
  std::uint16_t selected = 0;
  const GradientVolume* gradients = nullptr;
};

// The shares of the drawn rays in the mode's colour next to the structure and far from it (see
// above), for `settings` as they are (their unit, offset, reach and t); counts of the drawn rays in
// each set.
struct PictureColourShares {
  double near = 0, far = 0;
  std::size_t nearRays = 0, farRays = 0;
};
PictureColourShares pictureColourShares(const SceneVolumes& scene, const RenderSettings& settings);

// Judges fuzzy's unit, lighting's reach or outline's unit on the picture (see above) for
// `settings`' view and preset; `scale` holds what unitFromNeighbours set and the around set's
// median. `contextScale` multiplies every candidate unit as applyFieldScale applies it. Sets scale's unit (offset 0 when
// an around candidate wins) or lightingReach, pictureNear/pictureFar (the taken candidate's shares),
// pictureJudged, fromPicture, pictureAroundX (fuzzy), pictureShrink and pictureStretch (outline).
// Does nothing for another mode, without labels or a selected structure.
void scaleFromPicture(FieldScale& scale, const SceneVolumes& scene, const RenderSettings& settings,
                      double contextScale = 1.0);

}  // namespace at::render
