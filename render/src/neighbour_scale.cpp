#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "render/field_scale.h"
#include "view_rays.h"

namespace at::render {

namespace {

// The q-quantile (0 < q < 1) of d, reordering it.
double quantileOf(std::vector<float>& d, double q) {
  const auto at = d.begin() + std::ptrdiff_t(double(d.size() - 1) * q);
  std::nth_element(d.begin(), at, d.end());
  return *at;
}

double medianOf(std::vector<float>& d) { return quantileOf(d, 0.5); }

}  // namespace

NeighbourBone neighbourBone(const FloatVolume& field, const Volume& volume, const Mask* body, const BoneLevels& levels,
                            const FieldView& view) {
  NeighbourBone out;
  const Geometry& fg = field.geometry;
  const Geometry& vg = volume.geometry;
  if (vg.dims.count() == 0 || fg.dims.count() == 0) return out;
  const auto [w, h] = detail::rayGridOf(view.width, view.height, kScaleRaysPerSide);
  if (w < 1 || h < 1) return out;
  const double denseFrom = levels.dense, openBelow = std::min(levels.open, levels.dense);
  const bool bodyOnGrid = body && body->geometry.dims.count() == vg.dims.count();
  const double step = 0.5 * std::min({vg.spacingMm[0], vg.spacingMm[1], vg.spacingMm[2]});
  // One byte a ray (not vector<bool>'s shared words): rows are written by different threads.
  std::vector<char> structure(std::size_t(w) * std::size_t(h), 0);
  std::vector<float> first(structure.size(), 0);  // the first bone surface's D on each ray (0: none)
  forEachRowInParallel(h, [&, w = w, h = h](int py) {
    for (int px = 0; px < w; ++px) {
      const std::size_t i = std::size_t(py) * std::size_t(w) + std::size_t(px);
      const Ray ray = view.camera.rayThroughPixel(px, py, w, h);
      const detail::IndexRay rv = detail::indexRay(vg, ray), rf = detail::indexRay(fg, ray);
      double t0 = 0, t1 = 0;
      detail::boxSegment(rv, vg.dims, t0, t1);
      bool open = false;
      for (double t = t0 + 0.5 * step; t < t1; t += step) {
        if (view.clip && !view.clip->keeps(ray.origin + t * ray.direction)) continue;
        int vi[3], fi[3];
        if (!detail::voxelOn(rv, t, vg.dims, vi) || !detail::voxelOn(rf, t, fg.dims, fi)) continue;
        const float D = field.voxels[fg.dims.index(fi[0], fi[1], fi[2])];
        if (D == 0) {  // the structure: this pixel shows it
          structure[i] = 1;
          break;
        }
        if (first[i] > 0) continue;  // (a ray may still meet the structure behind its first bone)
        const std::size_t idx = vg.dims.index(vi[0], vi[1], vi[2]);
        const double value = double(volume.voxels[idx]);
        if (value <= openBelow) {
          open = true;
          continue;
        }
        if (value < denseFrom || !open) continue;
        open = false;
        if (bodyOnGrid && body->voxels[idx] == 0) continue;
        if (D > 0 && std::isfinite(D)) first[i] = D;
      }
    }
  });
  const std::vector<int> apart = detail::raysFromStructure(structure, w, h);
  const double side = double(std::max(w, h));
  std::vector<float> nearD, farD;
  for (std::size_t i = 0; i < structure.size(); ++i) {
    if (structure[i] || first[i] <= 0) continue;
    if (double(apart[i]) <= kNeighbourRing * side)
      nearD.push_back(first[i]);
    else if (double(apart[i]) >= kFarFromStructure * side)
      farD.push_back(first[i]);
  }
  out.nearRays = nearD.size();
  out.farRays = farD.size();
  if (!nearD.empty()) out.nearD = medianOf(nearD);
  if (!farD.empty()) {
    out.farD = medianOf(farD);
    out.farLowD = quantileOf(farD, kFarLowQuantile);
  }
  return out;
}

bool unitFromNeighbourBone(RenderMode mode) { return mode == RenderMode::Fuzzy || mode == RenderMode::Lighting; }

void unitFromNeighbours(FieldScale& scale, const NeighbourBone& bone, RenderMode mode) {
  scale.nearRingD = bone.nearD;
  scale.farRingD = bone.farD;
  const bool near = bone.nearRays >= kMinNeighbourRays && bone.nearD > 0;
  const bool far = bone.farRays >= kMinNeighbourRays && bone.farD > 0;
  if (mode == RenderMode::Fuzzy && near && (!far || bone.farD >= kNeighbourSeparates * bone.nearD)) {
    double unit = bone.nearD / kNeighbourX;
    if (far) unit = std::min(unit, bone.farD / kNeighbourFarX);
    scale.distanceUnit = std::max(1e-6, unit);
    scale.distanceOffset = 0;
    scale.fromNeighbours = true;
    scale.derived = true;
    return;
  }
  if (mode == RenderMode::Lighting && near && far && bone.farLowD >= kLightSeparates * bone.nearD) {
    double unit = (bone.farLowD - bone.nearD) / (kNeighbourFarX - kLightNearX);
    double offset = bone.nearD - kLightNearX * unit;
    if (offset < 0) {  // the far set's lower quartile more than 4.6 × as far as the near bone: no offset
      unit = bone.farLowD / kNeighbourFarX;
      offset = 0;
    }
    scale.distanceUnit = std::max(1e-6, unit);
    scale.distanceOffset = offset;
    scale.fromNeighbours = true;
    scale.derived = true;
    return;
  }
  // Fuzzy where the picture does not tell the bone next to the structure from the far bone, and
  // lighting where they are not far enough apart for the offset: the around set's unit stays,
  // shrunk (offset 0) only where it would colour the far bone.
  if (far && (bone.farD - scale.distanceOffset) / scale.distanceUnit < kNeighbourFarX) {
    scale.distanceUnit = std::max(1e-6, bone.farD / kNeighbourFarX);
    scale.distanceOffset = 0;
    scale.fromNeighbours = true;
  }
}

}  // namespace at::render
