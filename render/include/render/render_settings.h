// What one frame shows: the volumes (HU, labels, distance field, selected structure), the mode and
// preset, the camera and clipping plane. The GL ray caster (render/gl) and CPU picking read the same
// settings and classify samples the same way, so a pick returns what the user sees.
//
// Sample classification per mode (s = HU, D = distance field, D' = max(0, D − distanceOffset),
// n = f(D' / distanceUnit) = 2/(1+α^(D'/unit)); Eq. 6 below on D' too):
//   context (every mode but bare):
//     wdt, unweighted, outline, lighting: rgba = table(s, n), the 2-D TF of Algorithm 1.
//     fuzzy (Eqs. 4–5): w = distTF(n).A; K'd = Kd(1−w) + Kh·w interpolated in CIE XYZ, Kd = dataTF(s).RGB,
//         Kh = distTF(n).RGB (the highlight colour from a 1-D TF); A = lerp(t·dataTF(s).A, dataTF(s).A, w).
//     The opacity is then scaled by the surface ramp of the edge strength g (HU per voxel of the
//     smoothed volume, gradient_volume.h): A · lerp(interior, 1, smoothstep(lo, hi, g)), so edges
//     are drawn as surfaces and homogeneous regions do not pile up into fog. Context within about a
//     voxel of the selected structure (its smoothed mask > kMaskHalo) is not drawn, and context
//     between the eye and the structure's first surface along the ray counts at contextInFront of
//     its opacity, so the structure stays visible through the bone around it.
//   the selected structure (every mode): its mask, smoothed by a [1 2 1]³ binomial (a labelled voxel
//     it would drop below 0.5 raised to 0.75, so one-voxel-thin parts stay) and sampled
//     trilinearly, has a surface at 0.5; where a ray enters it one sample of highlight_rgb is
//     composited with opacity structure_opacity (bare: 1), and its inside draws nothing else.
//   bare: only the structure.
// Context opacity is per `opacityRefMm` of ray (default: one voxel) and corrected to the step:
// a' = 1 − (1 − a)^(step/ref). lighting adds Eq. 6: ambient k_a = β/(α_l·D/unit + 1)² in highlight
// colour, the structure as the light (α_l in the distance unit, as the distance TF's x).
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "render/camera.h"
#include "render/gradient_volume.h"
#include "render/preset.h"
#include "render/transfer_function.h"
#include "volume/grid.h"
#include "wdt/wdt.h"

namespace at::render {

struct RenderSettings {
  Preset preset;                       // TFs, t, α, highlight, lighting; preset.mode is the mode
  Camera camera;
  std::optional<ClipPlane> clip;
  int width = 512, height = 512;
  double stepMm = 0;                   // 0: kDefaultStepVoxels × the volume's smallest spacing
  double opacityRefMm = 0;             // TF opacity is per this length of ray; 0: the smallest spacing
  double distanceUnit = 1;             // weighted distances are divided by this before f(x) and Eq. 6;
                                       // framing sets it from the structure's size (scene.h), and once
                                       // the field is known from the field (field_scale.h)
  double distanceOffset = 0;           // D' = max(0, D − offset) is what the unit divides (field_scale.h:
                                       // a scan whose bone in view lies in a narrow band of D)
  double lightingReach = 1;            // lighting's Eq. 6 takes x = D' / (unit × reach): > 1 lights
                                       // farther without changing what the distance TF draws
                                       // (picture_scale.h, unitFromLightingPicture)
  std::array<float, 4> background{0, 0, 0, 0};  // composited under the volume (straight RGBA)
  bool jitter = true;                  // per-pixel ray start offsets (deterministic hash)
  bool shading = true;                 // Phong from gradients
  bool skipEmptySpace = true;          // GL: jump over blocks that cannot hold a visible sample
                                       // (same image; off marches every sample, for tests/benchmarks)
  int tableSize = 256;                 // entries per axis of the 2-D table

  bool operator==(const RenderSettings&) const = default;
};

// The default sampling step in voxels: with jittered starts, opacity correction and the structure's
// surface found by bisection, 0.75 voxel gives the image of 0.5 voxel (bench/RESULTS.md) at two
// thirds of the samples.
constexpr double kDefaultStepVoxels = 0.75;

// Context samples where the selected structure's smoothed mask exceeds this are not drawn.
constexpr float kMaskHalo = 0.02f;

// The selected structure's smoothed mask (as the GPU holds it: pick()'s per-voxel values, in
// 64ths) worked out once over the label's box grown by one voxel (0 outside it), so that a pick
// reads 8 values per sample instead of smoothing 8 × 27 labels. Gives the same numbers exactly.
struct SelectedMask {
  std::uint16_t label = 0;
  Dims dims;                          // of the label map it was made from
  std::array<int, 3> lo{0, 0, 0};     // the box (inclusive); hi < lo: empty
  std::array<int, 3> hi{-1, -1, -1};
  std::vector<std::uint8_t> sixtyFourths;  // box voxels, x fastest
  double at(std::size_t labelIndex) const;  // the value at a voxel of the label map
};
SelectedMask selectedMask(const LabelMap& labels, std::uint16_t label);

// What the ray caster samples. The field may lie on a coarser grid (downsampled); it is sampled
// trilinearly in the patient frame. `selected` is the label of the structure (0 = none).
struct SceneVolumes {
  const Volume* volume = nullptr;
  const LabelMap* labels = nullptr;     // same grid as volume
  const FloatVolume* field = nullptr;   // distance field on its own grid
  std::uint16_t selected = 0;
  const GradientVolume* gradients = nullptr;  // volume's; null: no surface ramp (every edge full)
  const SelectedMask* selectedMask = nullptr;  // selectedMask(*labels, selected), or null: smoothed per sample
};

// The 2-D table the mode samples (see the classification above). For bare mode it is the wdt
// table (unused by the shader but kept for picking consistency).
TransferFunction2D shadingTable(const Preset& preset);
// Whether two presets give the same shadingTable (their TFs, t and whether the mode is fuzzy):
// structures' presets that differ only in name, view or highlight share one table, so that a
// hover from one to another rebuilds neither the table nor what depends on it.
bool sameShadingTable(const Preset& a, const Preset& b);
// The last shadingTable asked for, kept while the presets asked for share it (a 256 × 256 table
// costs about a millisecond: too much to build again on every mouse move of a hover).
class ShadingTableCache {
 public:
  const TransferFunction2D& tableFor(const Preset& preset);

 private:
  std::optional<Preset> preset_;
  TransferFunction2D table_;
};
double effectiveStepMm(const Geometry& volumeGrid, const RenderSettings& settings);
double effectiveOpacityRefMm(const Geometry& volumeGrid, const RenderSettings& settings);
// Outline mode's band: the n at which the distance TF is most opaque; −1 for every other mode. Over
// each step the ray caster (and pick) use the n of the step nearest this one, so that a band in D
// thinner than a step is drawn where the ray crosses it instead of as speckle where a sample lands.
float outlineBandN(const Preset& preset);
// The surface ramp's factor for edge strength g (HU per voxel).
float surfaceFactor(const Preset& preset, float strength);
// The value the ray caster composites: opacity corrected from `opacityRefMm` to the step.
float correctedOpacity(float alpha, double stepMm, double refMm);
// sRGB display value ↔ CIE XYZ (D65), for the fuzzy mode's colour interpolation.
std::array<float, 3> srgbToXyz(const std::array<float, 3>& rgb);
std::array<float, 3> xyzToSrgb(const std::array<float, 3>& xyz);

struct PickResult {
  bool hit = false;
  std::uint16_t label = 0;   // label at the hit sample (0 if that sample is unlabelled)
  Vec3 pointMm{0, 0, 0};     // LPS
  double accumulatedOpacity = 0;
};

// Marches the ray through pixel (x, y) as the ray caster does (without jitter) and returns the
// first sample where accumulated opacity reaches `threshold`; hit = false when it never does.
PickResult pick(const SceneVolumes& scene, const RenderSettings& settings, const TransferFunction2D& table,
                double x, double y, double threshold = 0.5);

// pick() at two thresholds (`low` ≤ `high`) from one march: where the ray first shows something
// and where it turns opaque.
struct PickPair {
  PickResult low, high;
};
PickPair pickAtTwoThresholds(const SceneVolumes& scene, const RenderSettings& settings,
                             const TransferFunction2D& table, double x, double y, double low, double high);

// How much of pixel (x, y) is context: the opacity the context samples (everything but the
// selected structure's surface) add as the ray caster composites them front to back, 0…1. A pixel
// where the context is faded out, or lies behind the opaque structure, has ≈ 0.
double contextOpacity(const SceneVolumes& scene, const RenderSettings& settings, const TransferFunction2D& table,
                      double x, double y);

// The colour the ray caster composites at pixel (x, y), front to back, without its light (no
// gradient shading or specular; lighting mode's k_a of Eq. 6 is applied as the unshaded ray caster
// does): premultiplied rgb over no background, the accumulated opacity and the part of it the
// selected structure's surface adds. What a mode's colours show where, measured without a GPU.
struct CompositedPixel {
  std::array<double, 3> rgb{};
  double alpha = 0, structureAlpha = 0;
};
CompositedPixel compositePixel(const SceneVolumes& scene, const RenderSettings& settings, const TransferFunction2D& table,
                               double x, double y);

}  // namespace at::render
