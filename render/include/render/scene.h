// From a dataset, a selected structure and a preset to what the ray caster needs: the WDT
// parameters the preset asks for and a camera framing the structure with its context (the seed
// mask is volume/mask.h's structureMask).
// Shared by the `render` command, the benchmark, the figure script and the tests.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "render/render_settings.h"
#include "core/error.h"
#include "volume/grid.h"
#include "wdt/wdt.h"

namespace at::render {

struct StructureFrame {
  Vec3 centroidMm{0, 0, 0};   // LPS
  Vec3 anchorMm{0, 0, 0};     // the structure's voxel nearest its centroid: a point on it (the
                              // centroid of a curved structure, a spiral or a loop, lies outside it)
  double radiusMm = 0;        // farthest voxel centre from the centroid
  std::size_t voxelCount = 0;
  double volumeMm3 = 0;
  double voxelMm = 0;         // the grid's largest spacing
  std::array<int, 6> voxelBox{0, 0, 0, 0, 0, 0};  // its voxels' index box: x0 y0 z0 (inclusive) x1 y1 z1 (exclusive)
  // Voxel centres of the structure (every k-th, at most kMaxFramePoints), for framing from any side.
  std::vector<Vec3> pointsMm;
};
constexpr std::size_t kMaxFramePoints = 4096;

// Error if no voxel carries `label`.
Result<StructureFrame> structureFrame(const LabelMap& labels, std::uint16_t label);
// The same, reading only the voxels inside `box` (as voxelBox; clamped to the grid): equal to the
// whole map's frame when every voxel of `label` lies inside it (after an edit: the structure's
// previous voxelBox joined with the edited box), at the cost of the box alone.
Result<StructureFrame> structureFrame(const LabelMap& labels, std::uint16_t label, const std::array<int, 6>& box);

// One frame holding both structures (for framing: a view that must show `b` beside `a`, e.g. a
// locate question's target beside the region it is asked in): their points, the volume-weighted
// centroid, a radius reaching both, `a`'s anchor.
StructureFrame unionFrame(const StructureFrame& a, const StructureFrame& b);

// The context radius of a structure: the geometric mean of its equivalent-sphere radius (its
// volume's) and its farthest-voxel radius, in mm. A compact structure gets about its radius; a long
// thin one (a nerve, a canal) less than its length, so its context hugs it rather than filling the
// box around it. Phantom: cochlea ≈ 2.9 mm, a semicircular canal ≈ 2.2 mm; a vertebra ≈ 28 mm.
double contextRadiusMm(const StructureFrame& frame);
// The millimetre floors of framing and context (the view's least half-height, the distance unit's
// floor, the reach searched for context bone) are scaled by the frame's fineVoxelScale
// (volume/geometry.h): a structure of a µCT finer than 0.1 mm is framed and faded voxel for voxel
// as at 0.1 mm.
double fineVoxelScale(const StructureFrame& frame);

// The distance unit (RenderSettings::distanceUnit) for a structure: its context radius over
// kReferenceContextMm (the radius presets are written for, a cochlea's), times `scale`, clamped to
// 0.4..40 (the floor times fineVoxelScale) so that tiny or huge labels keep a usable context.
constexpr double kReferenceContextMm = 3.0;
double distanceUnitFor(const StructureFrame& frame, double scale = 1.0);

// A camera looking from the named side at the structure: centred on its extent as seen from that
// side and far enough (perspective included) that the extent times `margin` fills the view of the
// given aspect (width / height), and at least a view of half-height `minHalfHeightMm` times
// fineVoxelScale.
Camera frameCamera(const StructureFrame& frame, NamedView view, double aspect, double margin = 1.6,
                   double minHalfHeightMm = 3.0);
// The same from the side `orientation` looks from: its direction, up, field of view and projection
// are kept; its target and distance are replaced.
Camera frameCamera(const StructureFrame& frame, const Camera& orientation, double aspect, double margin = 1.6,
                   double minHalfHeightMm = 3.0);
// The share (0 … 1) of the structure's points (StructureFrame::pointsMm, else its centroid) that
// `camera` shows inside an image of width × height pixels.
double shareInView(const StructureFrame& frame, const Camera& camera, int width, int height);

// Step rule, HU window and base cost from the preset; uniform weights for the unweighted mode.
Result<WdtParams> wdtParamsFor(const Preset& preset, int passes = 2);

// Whether the mode samples a distance field (all but bare).
bool modeNeedsField(RenderMode mode);

struct ViewRequest {
  int width = 512, height = 512;
  std::optional<std::string> view;          // overrides preset.view; default lateral_left
  std::optional<std::array<float, 4>> clip; // overrides preset.clip
  double margin = 1.6;                      // the structure's extent times this fills the view
  double contextScale = 1.0;                // multiplies the structure's distance unit
  double minRadiusMm = 3;                   // smallest half-height of the view (times fineVoxelScale)
};

// Settings for rendering `preset` around the structure (framed camera, distance unit from its
// size); errors name a bad view or clip plane.
Result<RenderSettings> settingsFor(const Preset& preset, const StructureFrame& frame, const ViewRequest& request);

}  // namespace at::render
