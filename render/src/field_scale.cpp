#include "render/field_scale.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace at::render {

double denseLevel(const Preset& preset) {
  float peak = 0;
  for (const TfPoint& p : preset.dataTf) peak = std::max(peak, p.rgba[3]);
  if (peak <= 0) return preset.dataTf.empty() ? 0.0 : preset.dataTf.back().x;
  // The first x where the piecewise-linear opacity reaches half the peak.
  for (std::size_t i = 0; i < preset.dataTf.size(); ++i) {
    const TfPoint& b = preset.dataTf[i];
    if (b.rgba[3] < 0.5f * peak) continue;
    if (i == 0) return b.x;
    const TfPoint& a = preset.dataTf[i - 1];
    const double u = (0.5 * peak - a.rgba[3]) / std::max(1e-6, double(b.rgba[3] - a.rgba[3]));
    return a.x + std::clamp(u, 0.0, 1.0) * (b.x - a.x);
  }
  return preset.dataTf.back().x;
}

double openLevel(const Preset& preset) {
  // The last point before the first with opacity: everything up to it is drawn clear.
  if (preset.dataTf.empty()) return 0;
  double level = preset.dataTf.front().x;
  for (const TfPoint& p : preset.dataTf) {
    if (p.rgba[3] > 0) break;
    level = p.x;
  }
  return level;
}

BoneLevels boneLevels(const Preset& preset) { return {denseLevel(preset), openLevel(preset)}; }

FieldScale fieldScale(const FloatVolume& field, const Volume& volume, const Mask* body, const StructureFrame& frame,
                      const BoneLevels& levels, double margin, double minRadiusMm) {
  const double denseFrom = levels.dense, openBelow = std::min(levels.open, levels.dense);
  FieldScale out;
  out.distanceUnit = distanceUnitFor(frame);
  const Geometry& fg = field.geometry;
  const Geometry& vg = volume.geometry;
  const double reach = std::max(minRadiusMm, margin * frame.radiusMm);
  // The reach's box in field indices (the corners of the sphere's bounding box, any orientation).
  int lo[3] = {fg.dims.x, fg.dims.y, fg.dims.z}, hi[3] = {-1, -1, -1};
  for (int corner = 0; corner < 8; ++corner) {
    const Vec3 p = frame.centroidMm + Vec3{(corner & 1) ? reach : -reach, (corner & 2) ? reach : -reach,
                                           (corner & 4) ? reach : -reach};
    const Vec3 ijk = fg.patientToIndex(p);
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], int(std::floor(ijk[a])));
      hi[a] = std::max(hi[a], int(std::ceil(ijk[a])));
    }
  }
  const int n[3] = {fg.dims.x, fg.dims.y, fg.dims.z};
  double boxCount = 1;
  for (int a = 0; a < 3; ++a) {
    lo[a] = std::max(lo[a], 0);
    hi[a] = std::min(hi[a], n[a] - 1);
    if (hi[a] < lo[a]) return out;
    boxCount *= double(hi[a] - lo[a] + 1);
  }
  const int stride = std::max(1, int(std::ceil(std::cbrt(boxCount / double(kMaxScaleSamples)))));
  const int vn[3] = {vg.dims.x, vg.dims.y, vg.dims.z};
  const bool bodyOnGrid = body && body->geometry.dims.count() == vg.dims.count();
  std::vector<float> d;
  d.reserve(std::size_t(std::min(boxCount, double(kMaxScaleSamples))));
  for (int k = lo[2]; k <= hi[2]; k += stride)
    for (int j = lo[1]; j <= hi[1]; j += stride)
      for (int i = lo[0]; i <= hi[0]; i += stride) {
        const float D = field.voxels[fg.dims.index(i, j, k)];
        if (!(D > 0) || !std::isfinite(D)) continue;
        const Vec3 p = fg.indexToPatient({double(i), double(j), double(k)});
        if (norm(p - frame.centroidMm) > reach) continue;
        const Vec3 v = vg.patientToIndex(p);
        int vi[3];
        bool inside = true;
        for (int a = 0; a < 3; ++a) {
          vi[a] = int(std::lround(v[a]));
          inside = inside && vi[a] >= 0 && vi[a] < vn[a];
        }
        if (!inside) continue;
        const std::size_t idx = vg.dims.index(vi[0], vi[1], vi[2]);
        if (double(volume.voxels[idx]) < denseFrom) continue;
        // Only the bone's outer surfaces are seen: a dense voxel with open space (drawn clear)
        // within kOpenReach voxels along an axis. Walls of marrow (dense next to medium values)
        // lie inside the bone, behind its outer surface.
        bool surface = false;
        for (int a = 0; a < 3 && !surface; ++a)
          for (int s = -kOpenReach; s <= kOpenReach && !surface; ++s) {
            if (s == 0) continue;
            int w[3] = {vi[0], vi[1], vi[2]};
            w[a] += s;
            if (w[a] < 0 || w[a] >= vn[a]) continue;
            surface = double(volume.voxels[vg.dims.index(w[0], w[1], w[2])]) <= openBelow;
          }
        if (!surface) continue;
        if (bodyOnGrid && body->voxels[idx] == 0) continue;
        d.push_back(D);
      }
  out.contextVoxels = d.size();
  if (d.size() < 64) return out;
  const auto q = d.begin() + std::ptrdiff_t(kContextQuantile * double(d.size() - 1));
  std::nth_element(d.begin(), q, d.end());
  out.quantileD = *q;
  const auto qFar = d.begin() + std::ptrdiff_t(kFarQuantile * double(d.size() - 1));
  std::nth_element(q, qFar, d.end());
  out.farQuantileD = *qFar;
  out.distanceUnit = std::max(1e-6, out.quantileD / kContextQuantileX);
  // A narrow spread (the far quantile short of kFarQuantileX): the map D → x is stretched about the
  // context quantile so the far quantile lands at kFarQuantileX, x = (D − offset) / unit.
  const double spread = out.farQuantileD - out.quantileD;
  if (spread > 0 && spread / out.distanceUnit < kFarQuantileX - kContextQuantileX) {
    out.distanceUnit = std::max(1e-6, spread / (kFarQuantileX - kContextQuantileX));
    out.distanceOffset = std::max(0.0, out.quantileD - kContextQuantileX * out.distanceUnit);
  }
  out.derived = true;
  return out;
}

}  // namespace at::render
