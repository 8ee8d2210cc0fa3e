// The distance unit of a field, in the field's own (weighted millimetre) units, derived from the
// field and the data rather than from the structure's size.
//
// Why: a weighted distance D sums weight × path length, and the weight is small in air and soft
// tissue (the preset's base plus the HU window's share). How large D gets for the bone a user sees
// around a structure depends on the voxel size, the window, the tissue in between and the scan —
// on a 0.1 mm phantom the bone in view lies at D ≈ 1…8, on a 1 mm head CT the whole framed view
// lies within D ≈ 1 of the mandible. A unit fixed in millimetres (or taken from the structure's
// size) puts every voxel of a real scan in the distance TF's "near" band, so t does nothing.
//
// The unit (and offset, see kFarQuantileX) is measured on two sets of bone surfaces within the
// framed view's reach (a sphere about the structure's centroid of radius margin × its radius, at
// least minRadiusMm times fineVoxelScale), each a bone surface as the preset's data TF draws it
// (stored value at or above the level where the data TF reaches half its peak opacity, next to
// open space — at or below the level the data TF draws clear: the walls of marrow cavities lie
// inside the bone), inside the body when a body mask is given (the CT table and headrest are no context), reachable
// (finite D) and not the structure (D > 0):
//  - around: every such surface voxel in the sphere (kOpenReach voxels to open space along an
//    axis): the bone the structure is embedded in, seen or not;
//  - seen (only with a FieldView: the camera, image size and clip plane of the framed view): the
//    first bone surface each ray of the view meets inside the sphere; rays that meet the structure
//    count nothing (that pixel shows the structure; the bone in front is drawn faint).
// The unit is taken from whichever set lies nearer (smaller median D), so that the farther half of
// the bone the user sees fades out at t = 0 in both kinds of view:
//  - a structure that hides the bone behind it (the abdominal CT's right kidney from the front
//    hides the ribs behind it): the seen surfaces (median D 5.9) lie nearer than all those around
//    it (7.8); scaled on those around, the bone in view sat at x ≈ 1.3, all drawn at t = 0, and t
//    changed the image by 3 grey levels;
//  - a structure embedded in bone (the orbit, the ear canal, the µCT labyrinth): the first surface
//    each ray meets is the outer shell (far in D) and the bone around the structure lies behind
//    it; scaled on the seen surfaces the shell stayed drawn at t = 0 (the orbit's t change fell
//    from 39.5 to 14.8 grey levels, the µCT cochlea drew 73 % of the frame at t = 0).
// The unit is the chosen set's kContextQuantile quantile of D divided by kContextQuantileX, so
// that quantile lands at x = kContextQuantileX of the presets' f(x) = 2/(1+α^x): with the
// shipped and derived distance TFs (full within x ≈ 1.1, half at x ≈ 2.6, gone by x ≈ 4.7) the
// nearer half of that bone is context at t = 0 and the farther half fades out inside the view, on
// any scan and voxel size — and the slider t brings that farther half in. The shipped presets' x
// (and lighting's α of Eq. 6, applied to D / unit) are in this unit.
//
// With the view (WDT and non-weighted), what the user sees drawn is checked per pixel too: a pixel
// shows context at t = 0 when the nearest bone its ray crosses lies at x < drawnToX. Where bone
// surrounds the structure every ray crosses some of the nearer half of the bone, so the unit above
// drew 71–82 % of the µCT's labyrinth and facial-nerve frames; there the unit is shrunk (offset 0)
// until at most kMaxDrawnShare of the pixels, the structure's included, would be drawn.
//
// Cost: one pass over the field's voxels inside the reach's box (a subsample of at most
// kMaxScaleSamples of them) and at most kScaleRaysPerSide² rays marched at half the smallest voxel
// spacing through the reach (and once more, a voxel per step, through the volume), done once per
// field and framed view — not per frame.
#pragma once

#include <cstddef>
#include <limits>
#include <optional>

#include "render/camera.h"
#include "render/preset.h"
#include "render/render_settings.h"
#include "render/scene.h"
#include "volume/grid.h"

namespace at::render {

constexpr double kContextQuantile = 0.5;
// x of the median bone in view: 2.6 units, where the distance TFs are at half opacity. (1.9, where
// they are still at about 0.8, kept the phantom's size-based units but left 60–90 % of the frame
// drawn at t = 0 around the skull's sinuses and ear canal, and little for t to add on the abdomen.)
constexpr double kContextQuantileX = 2.6;
// The far quantile of the bone in view lands at x ≥ kFarQuantileX (f = 0.2: where the shipped and
// derived distance TFs have faded out, so at t = 0 the farthest tenth of the bone in view is gone). Where the bone's weighted distances are spread narrowly —
// on an abdominal CT every bone is reached through the same soft tissue, D of the 10th to the 90th
// percentile within a factor 2.3 — no bone is far at x = D / unit, so nothing fades and t adds
// nothing; there the map is stretched about the context quantile: x = (D − offset) / unit.
constexpr double kFarQuantile = 0.9;
constexpr double kFarQuantileX = 4.7;
constexpr std::size_t kMaxScaleSamples = 1u << 18;
// A dense voxel is an outer surface when open space lies within this many voxels along an axis
// (two: a partial-volume voxel between bone and air is not open itself).
constexpr int kOpenReach = 2;
// The seen set: rays along the view's longer side, and the fewest first surfaces it must hold.
constexpr int kScaleRaysPerSide = 128;
constexpr std::size_t kMinSeenSurfaces = 64;
// At most this share of the view's pixels show the structure or context at t = 0 (with a
// FieldView). A pixel shows context when the nearest bone its ray crosses lies at a small x, so
// where bone surrounds the structure (the µCT's labyrinth and facial nerve in the petrous bone)
// every ray crosses some of the nearer half of the bone: with the unit from the surfaces alone
// 71 % and 82 % of those frames were drawn at t = 0. Each ray's nearest bone (whole ray, dense
// voxels) is measured; where more than this share would be drawn (nearest bone at x <
// BoneLevels::drawnToX), the unit is shrunk until the rays beyond this share have it at drawnToX —
// but at least kMinDrawnBoneShare of the rays that cross bone stay drawn.
constexpr double kMaxDrawnShare = 0.45;
constexpr double kMinDrawnBoneShare = 0.25;

struct FieldScale {
  double distanceUnit = 1;      // (D − distanceOffset) / distanceUnit is the presets' x (clamped at 0)
  double distanceOffset = 0;    // 0 unless the spread is narrow (kFarQuantileX)
  double farQuantileD = 0;      // the measured kFarQuantile quantile of D
  double quantileD = 0;         // the measured quantile of D over the context voxels
  std::size_t contextVoxels = 0;  // voxels (or seen surfaces) the quantile was taken over (0: fell back)
  bool derived = false;         // false: too few context voxels, the size-based unit is kept
  bool fromSeen = false;        // the unit was taken from the bone surfaces the view sees first
  double aroundQuantileD = 0;   // the median D of each set (0: not measured or too few)
  double seenQuantileD = 0;
  // The view's rays (with a FieldView): how many were cast, the share that cross bone and not the
  // structure, the D beyond which their nearest bone must fade (0: no cap needed), and whether
  // that cap set the unit (kMaxDrawnShare).
  std::size_t viewRays = 0;
  double boneRayShare = 0;
  double drawnLimitD = 0;
  bool cappedByRays = false;
  // Fuzzy and lighting (unitFromNeighbourBone): the median D of the bone seen next to the structure
  // and far from it in the picture (0: not measured), and whether they set the unit.
  double nearRingD = 0, farRingD = 0;
  bool fromNeighbours = false;
  // Fuzzy, lighting and outline with the picture's inputs (picture_scale.h): the shares of the
  // context next to the structure and far from it drawn in the mode's colour at t = pictureT(mode)
  // with the unit and reach taken, whether the picture chose them, then at which x fuzzy's unit put
  // the around set's median, the factor the kept unit (fuzzy) or reach (lighting) was shrunk by
  // (1: not shrunk), and lighting's reach (Eq. 6 on D' / (unit × reach)).
  double pictureNear = 0, pictureFar = 0;
  bool pictureJudged = false;  // the shares were measured (judgedOnPicture, with its inputs)
  bool fromPicture = false;
  double pictureAroundX = 0;
  double pictureShrink = 1;
  // Outline: the factor the unit was stretched by so the band reaches bone the view shows (1: not).
  double pictureStretch = 1;
  double lightingReach = 1;
};

// The stored-value level from which the preset's data TF draws bone: the first TF x at which its
// opacity reaches half of its peak.
double denseLevel(const Preset& preset);
// The level up to which the preset's data TF draws nothing (its last zero-opacity point before the
// first drawn one): air, fat and soft tissue on the shipped and derived presets, not marrow.
double openLevel(const Preset& preset);

// The x (distance units) beyond which the preset draws a bone sample faintly at t = 0: its data
// TF's peak opacity × the distance TF's opacity κ² (Algorithm 1 at t = 0) under kFaintOpacity.
// Infinity where the distance TF never clears (nothing fades with distance).
constexpr double kFaintOpacity = 0.1;
double drawnToX(const Preset& preset);

// What counts as the bone a user sees: dense voxels (≥ dense) with open space (≤ open) near them;
// and up to which x it is drawn at t = 0 (drawnToX).
struct BoneLevels {
  double dense = 0, open = 0;
  double drawnToX = std::numeric_limits<double>::infinity();
  bool operator==(const BoneLevels&) const = default;
};
BoneLevels boneLevels(const Preset& preset);

// The view the seen set is measured in (RenderSettings' camera, size and clip plane).
struct FieldView {
  Camera camera;
  int width = 512, height = 512;
  std::optional<ClipPlane> clip;
  bool operator==(const FieldView&) const = default;
};
FieldView fieldViewOf(const RenderSettings& settings);

// The field's unit for a structure (see above). `volume` is the scan the field was computed on
// (any grid: it is sampled at the field's voxel centres and along the rays); `body` (on the
// volume's grid) may be null; `view` null measures the around set only. With fewer than 64
// context voxels (and kMinSeenSurfaces seen surfaces) the size-based unit (distanceUnitFor) is
// returned, derived = false.
FieldScale fieldScale(const FloatVolume& field, const Volume& volume, const Mask* body, const StructureFrame& frame,
                      const BoneLevels& levels, const FieldView* view, double margin = 1.6, double minRadiusMm = 3.0);

// Whether a mode's unit may come from the seen set: only where the unit sets how the context fades
// with distance (WDT and non-weighted). Outline marks the bone near the structure with a band:
// measured on the bone around it, the band stays put when the view turns (unless the view shows
// no band at that unit: picture_scale.h then stretches it). (Fuzzy and lighting take
// their unit from the bone seen next to the structure instead: unitFromNeighbours.) (From the seen set the skull's frontal sinus, seen from the front
// through the thin anterior wall, lost its band: 0.6 % of the frame, 21.9 % isolated pixels.)
bool unitFromSeenBone(RenderMode mode);

// Fuzzy (Fig. 5) and lighting (Fig. 7) colour the bone the user sees next to the structure: the
// colour must stay confined to the structure's neighbourhood in the picture. Both measure the view:
// the first bone surface each ray of the framed view meets (entered from open space), split by how
// far the ray passes from the structure's silhouette in the picture (rays that meet the structure
// are the silhouette): the median D of the rays within kNeighbourRing of it (near) and of those
// beyond kFarFromStructure (far).
//  - Fuzzy, where the picture tells the two apart (far median ≥ kNeighbourSeparates × near): the
//    near median lands at x = kNeighbourX (0.7 of the full colour) and the far one at x ≥
//    kNeighbourFarX (no colour beyond x ≈ 2.8, faint from x ≈ 2), the smaller unit winning.
//    On the around set alone the skull's mastoid cells coloured 9 % of the bone next to them: the
//    bone around cells embedded in bone is mostly hidden (septa, the petrous bone) and nearer in D
//    than the surface seen next to them, which sat at x ≈ 1.9.
//  - Lighting, where the picture tells the two apart well (the far set's lower quartile, farLowD,
//    at least kLightSeparates × the near median): an offset and a unit that put the near median at
//    x = kLightNearX and that quartile at x = kNeighbourFarX (offset 0 where the quartile is more
//    than 4.6 × as far). With the derived α (2.9) k_a = β/(αx + 1)² is then 1.8 on the bone
//    touching the structure (D below the offset), 0.3 on the bone next to it and at most 0.03 on
//    three quarters of the far bone, drawn dim and neutral. Without the offset (the around set's
//    unit, capped only so the far median lay at kNeighbourFarX) the skull's zygomatic arch lit the
//    bone at its roots with k_a 0.12. Where the two are closer (the skull's right arch from the side
//    and frontal sinus from the front: quartile 1.9 and 1.5 × the near median) the offset lit the
//    far bone behind the translucent surface too: 19 and 41 % of the far pixels in its colour.
//  - Fuzzy where near and far are alike, and lighting where they are not far enough apart: the
//    around set's unit stays, shrunk (offset 0) only so the far median lies at x ≥ kNeighbourFarX.
//    The bone seen next to a structure embedded in bone is often the outer shell above it, as far in D as
//    the rest (the phantom's lateral canal from above: near and far medians 5.8, against 1.0 for
//    the bone around it; scaled on them the whole shell was lit).
// What no unit fixes: where the bone seen far from the structure is as near in D as the bone next
// to it (the skull's orbit from the front: the ethmoid cells and the nasal cavity are reached
// through the paper-thin medial wall, the far median only 1.3 × the near one), a colour on the near
// bone reaches the far bone as much; the far cap keeps both faint (confined, but little colour).
// A structure embedded in bone: inside the µCT-like phantom (uint8, 0.1 mm, from above) the shell
// over the labyrinth is the first bone each ray meets, next to the structure and far from it alike
// (D 3.4 and 3.3 for the lateral canal, 5.2 × the median of the bone around it), and with the unit
// from it fuzzy colours 7 % of the context next to the canal. A rule from these measures alone
// (seen bone ≥ 2 × the around median: the around median at x = kNeighbourX) coloured 41 % there,
// but on the skull CT it also picked the sphenoid sinus, the axis and the left coronoid process and
// coloured more of their far bone than of the near (sphenoid from the right: 13 % near, 23 % far).
// Which unit confines the colour depends on what lies in front of what, so with the picture's
// inputs fuzzy's unit is judged on the picture itself (picture_scale.h). Lighting cannot gain from
// the unit there: the unit also sets the opacity, and one that lights the bone around the structure
// leaves the shell over it opaque and dark; its reach (Eq. 6's x alone) is judged on the picture.
constexpr double kNeighbourRing = 0.05;      // of the ray grid's longer side (8 px of 160)
constexpr double kFarFromStructure = 0.19;   // (30 px of 160)
constexpr double kNeighbourX = 1.15;
constexpr double kNeighbourFarX = 2.3;
constexpr double kNeighbourSeparates = 1.4;
constexpr double kLightNearX = 0.5;
constexpr double kFarLowQuantile = 0.25;
constexpr double kLightSeparates = 2.0;
constexpr std::size_t kMinNeighbourRays = 32;
struct NeighbourBone {
  double nearD = 0, farD = 0;  // median D of each set's first surfaces (0: none)
  double farLowD = 0;          // the far set's kFarLowQuantile quantile (0: none)
  std::size_t nearRays = 0, farRays = 0;
};
NeighbourBone neighbourBone(const FloatVolume& field, const Volume& volume, const Mask* body, const BoneLevels& levels,
                            const FieldView& view);
bool unitFromNeighbourBone(RenderMode mode);
// Sets `scale`'s unit from `bone` as above (sets counted only with kMinNeighbourRays rays).
void unitFromNeighbours(FieldScale& scale, const NeighbourBone& bone, RenderMode mode);

// The one way every front end (render command, desktop, terminal pictures, default views, question
// checks) sets a framed view's distance unit: fieldScale on `settings`' own view (camera, size,
// clip: set them first; the view only where unitFromSeenBone(settings.preset.mode)) with the
// request's margin, for fuzzy and lighting then unitFromNeighbours on the same view and, with
// `picture` (its labels and structure), scaleFromPicture (picture_scale.h), then distanceUnit =
// unit × request.contextScale, distanceOffset and lightingReach. Returns the measure.
struct PictureInputs;
FieldScale applyFieldScale(RenderSettings& settings, const FloatVolume& field, const Volume& volume, const Mask* body,
                           const StructureFrame& frame, const ViewRequest& request,
                           const PictureInputs* picture = nullptr);

}  // namespace at::render
