// From a dataset, a selected structure and a preset to what the ray caster needs: the WDT
// parameters the preset asks for and a camera framing the structure with its context (the seed
// mask is volume/mask.h's structureMask).
// Shared by the `render` command, the benchmark, the figure script and the tests.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "render/render_settings.h"
#include "core/error.h"
#include "volume/grid.h"
#include "wdt/wdt.h"

namespace at::render {

struct StructureFrame {
  Vec3 centroidMm{0, 0, 0};   // LPS
  double radiusMm = 0;        // farthest voxel centre from the centroid
  std::size_t voxelCount = 0;
};

// Error if no voxel carries `label`.
Result<StructureFrame> structureFrame(const LabelMap& labels, std::uint16_t label);

// Step rule, HU window and base cost from the preset; uniform weights for the unweighted mode.
Result<WdtParams> wdtParamsFor(const Preset& preset, int passes = 2);

// Whether the mode samples a distance field (all but bare).
bool modeNeedsField(RenderMode mode);

struct ViewRequest {
  int width = 512, height = 512;
  std::optional<std::string> view;          // overrides preset.view; default lateral_left
  std::optional<std::array<float, 4>> clip; // overrides preset.clip
  double contextScale = 2.5;                // view radius = max(contextScale · structure radius, minRadiusMm)
  double minRadiusMm = 6;
};

// Settings for rendering `preset` around the structure; errors name a bad view or clip plane.
Result<RenderSettings> settingsFor(const Preset& preset, const StructureFrame& frame, const ViewRequest& request);

}  // namespace at::render
