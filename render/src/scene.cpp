#include "render/scene.h"

#include <algorithm>
#include <cmath>

namespace at::render {

Result<StructureFrame> structureFrame(const LabelMap& labels, std::uint16_t label) {
  const Geometry& g = labels.geometry;
  const Dims& d = g.dims;
  StructureFrame f;
  double s[3] = {0, 0, 0};
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i)
        if (labels.voxels[d.index(i, j, k)] == label) {
          s[0] += i;
          s[1] += j;
          s[2] += k;
          ++f.voxelCount;
        }
  if (f.voxelCount == 0) return fail("structure label " + std::to_string(label) + " has no voxels");
  const double n = double(f.voxelCount);
  const Vec3 cIdx{s[0] / n, s[1] / n, s[2] / n};
  f.centroidMm = g.indexToPatient(cIdx);
  double r2 = 0;
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i)
        if (labels.voxels[d.index(i, j, k)] == label) {
          const Vec3 p = g.indexToPatient({double(i), double(j), double(k)});
          r2 = std::max(r2, dot(p - f.centroidMm, p - f.centroidMm));
        }
  f.radiusMm = std::sqrt(r2);
  return f;
}

Result<WdtParams> wdtParamsFor(const Preset& preset, int passes) {
  WdtParams p;
  auto rule = parseStepRule(preset.weightRule);
  if (!rule) return tl::unexpected(rule.error());
  p.rule = *rule;
  p.weight = preset.mode == RenderMode::Unweighted ? WeightRule::Uniform : WeightRule::Density;
  p.huMin = preset.huWindow[0];
  p.huMax = preset.huWindow[1];
  p.baseCost = preset.weightBase;
  p.passes = passes;
  return p;
}

bool modeNeedsField(RenderMode mode) { return mode != RenderMode::Bare; }

Result<RenderSettings> settingsFor(const Preset& preset, const StructureFrame& frame, const ViewRequest& request) {
  RenderSettings s;
  s.preset = preset;
  s.width = request.width;
  s.height = request.height;
  const std::string view = request.view ? *request.view : preset.view.value_or("lateral_left");
  const double radius = std::max(request.contextScale * frame.radiusMm, request.minRadiusMm);
  auto cam = Camera::named(view, frame.centroidMm, radius);
  if (!cam) return tl::unexpected(cam.error());
  s.camera = *cam;
  const auto clip = request.clip ? request.clip : preset.clip;
  if (clip) {
    auto plane = ClipPlane::fromCoefficients((*clip)[0], (*clip)[1], (*clip)[2], (*clip)[3]);
    if (!plane) return tl::unexpected(plane.error());
    s.clip = *plane;
  }
  return s;
}

}  // namespace at::render
