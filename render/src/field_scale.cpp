#include "render/field_scale.h"

#include <algorithm>
#include <cmath>
#include <limits>
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

namespace {

// The unit and offset from the chosen set's quantiles (see kFarQuantileX).
void unitFromQuantiles(FieldScale& out) {
  out.distanceUnit = std::max(1e-6, out.quantileD / kContextQuantileX);
  out.distanceOffset = 0;
  // A narrow spread (the far quantile short of kFarQuantileX): the map D → x is stretched about the
  // context quantile so the far quantile lands at kFarQuantileX, x = (D − offset) / unit.
  const double spread = out.farQuantileD - out.quantileD;
  if (spread > 0 && spread / out.distanceUnit < kFarQuantileX - kContextQuantileX) {
    out.distanceUnit = std::max(1e-6, spread / (kFarQuantileX - kContextQuantileX));
    out.distanceOffset = std::max(0.0, out.quantileD - kContextQuantileX * out.distanceUnit);
  }
}

struct Quantiles {
  double context = 0, far = 0;
  std::size_t count = 0;
};
Quantiles quantilesOf(std::vector<float>& d) {
  Quantiles q;
  q.count = d.size();
  if (d.empty()) return q;
  const auto mid = d.begin() + std::ptrdiff_t(kContextQuantile * double(d.size() - 1));
  std::nth_element(d.begin(), mid, d.end());
  q.context = *mid;
  const auto far = d.begin() + std::ptrdiff_t(kFarQuantile * double(d.size() - 1));
  std::nth_element(mid, far, d.end());
  q.far = *far;
  return q;
}

// The around set: D of every bone surface voxel in the reach (a subsample of the reach's box).
std::vector<float> aroundSurfaces(const FloatVolume& field, const Volume& volume, const Mask* body,
                                  const StructureFrame& frame, double denseFrom, double openBelow, double reach) {
  std::vector<float> d;
  const Geometry& fg = field.geometry;
  const Geometry& vg = volume.geometry;
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
    if (hi[a] < lo[a]) return d;
    boxCount *= double(hi[a] - lo[a] + 1);
  }
  const int stride = std::max(1, int(std::ceil(std::cbrt(boxCount / double(kMaxScaleSamples)))));
  const int vn[3] = {vg.dims.x, vg.dims.y, vg.dims.z};
  const bool bodyOnGrid = body && body->geometry.dims.count() == vg.dims.count();
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
        // Only the bone's outer surfaces: a dense voxel with open space (drawn clear) within
        // kOpenReach voxels along an axis. Walls of marrow (dense next to medium values) lie
        // inside the bone, behind its outer surface.
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
  return d;
}

// Index-space position along a ray: origin + t · perMm.
struct IndexRay {
  Vec3 origin, perMm;
};
IndexRay indexRay(const Geometry& g, const Ray& r) {
  const Vec3 o = g.patientToIndex(r.origin);
  return {o, g.patientToIndex(r.origin + r.direction) - o};
}
bool voxelOn(const IndexRay& r, double t, const Dims& dims, int ijk[3]) {
  const int n[3] = {dims.x, dims.y, dims.z};
  for (int a = 0; a < 3; ++a) {
    ijk[a] = int(std::lround(r.origin[a] + t * r.perMm[a]));
    if (ijk[a] < 0 || ijk[a] >= n[a]) return false;
  }
  return true;
}

// The seen set: D of the first bone surface (entered from open space) each ray of the view meets
// inside the reach; a ray that meets the structure (D = 0) counts nothing.
std::vector<float> seenSurfaces(const FloatVolume& field, const Volume& volume, const Mask* body,
                                const StructureFrame& frame, double denseFrom, double openBelow, double reach,
                                const FieldView& view) {
  std::vector<float> d;
  const Geometry& fg = field.geometry;
  const Geometry& vg = volume.geometry;
  if (view.width < 1 || view.height < 1) return d;
  const bool bodyOnGrid = body && body->geometry.dims.count() == vg.dims.count();
  const double step = 0.5 * std::min({vg.spacingMm[0], vg.spacingMm[1], vg.spacingMm[2]});
  // At most kScaleRaysPerSide rays along the longer side, at pixel centres of an image of the same
  // aspect (the same frustum).
  const double shrink = std::min(1.0, double(kScaleRaysPerSide) / double(std::max(view.width, view.height)));
  const int w = std::max(1, int(std::lround(view.width * shrink))), h = std::max(1, int(std::lround(view.height * shrink)));
  for (int py = 0; py < h; ++py)
    for (int px = 0; px < w; ++px) {
      const Ray ray = view.camera.rayThroughPixel(px, py, w, h);
      // The reach's segment of the ray (|origin + t·direction − centroid| ≤ reach).
      const Vec3 oc = ray.origin - frame.centroidMm;
      const double b = dot(oc, ray.direction), c = dot(oc, oc) - reach * reach, disc = b * b - c;
      if (disc <= 0) continue;
      const double t0 = std::max(0.0, -b - std::sqrt(disc)), t1 = -b + std::sqrt(disc);
      const IndexRay rv = indexRay(vg, ray), rf = indexRay(fg, ray);
      bool open = false;
      float first = 0;  // the first surface's D (0: none yet)
      for (double t = t0 + 0.5 * step; t < t1; t += step) {
        if (view.clip && !view.clip->keeps(ray.origin + t * ray.direction)) continue;
        int vi[3], fi[3];
        if (!voxelOn(rv, t, vg.dims, vi)) continue;
        const float D = voxelOn(rf, t, fg.dims, fi) ? field.voxels[fg.dims.index(fi[0], fi[1], fi[2])]
                                                    : std::numeric_limits<float>::infinity();
        if (D == 0) {  // the structure: this pixel shows it (the bone in front is drawn faint)
          first = 0;
          break;
        }
        if (first > 0) continue;
        const std::size_t idx = vg.dims.index(vi[0], vi[1], vi[2]);
        const double value = double(volume.voxels[idx]);
        if (value <= openBelow) {
          open = true;
          continue;
        }
        if (value < denseFrom || !open) continue;
        open = false;  // entering bone from open space: an outer surface the ray crosses
        if (bodyOnGrid && body->voxels[idx] == 0) continue;
        if (D > 0 && std::isfinite(D)) first = D;
      }
      if (first > 0) d.push_back(first);
    }
  return d;
}

}  // namespace

FieldView fieldViewOf(const RenderSettings& settings) {
  return {settings.camera, settings.width, settings.height, settings.clip};
}

FieldScale fieldScale(const FloatVolume& field, const Volume& volume, const Mask* body, const StructureFrame& frame,
                      const BoneLevels& levels, const FieldView* view, double margin, double minRadiusMm) {
  const double denseFrom = levels.dense, openBelow = std::min(levels.open, levels.dense);
  FieldScale out;
  out.distanceUnit = distanceUnitFor(frame);
  if (volume.geometry.dims.count() == 0 || field.geometry.dims.count() == 0) return out;
  const double reach = std::max(minRadiusMm, margin * frame.radiusMm);
  std::vector<float> around = aroundSurfaces(field, volume, body, frame, denseFrom, openBelow, reach);
  const Quantiles a = quantilesOf(around);
  Quantiles s;
  if (view) {
    std::vector<float> seen = seenSurfaces(field, volume, body, frame, denseFrom, openBelow, reach, *view);
    s = quantilesOf(seen);
  }
  const bool aroundOk = a.count >= 64, seenOk = s.count >= kMinSeenSurfaces;
  if (aroundOk) out.aroundQuantileD = a.context;
  if (seenOk) out.seenQuantileD = s.context;
  if (!aroundOk && !seenOk) {
    out.contextVoxels = std::max(a.count, s.count);
    return out;
  }
  out.fromSeen = seenOk && (!aroundOk || s.context < a.context);
  const Quantiles& q = out.fromSeen ? s : a;
  out.quantileD = q.context;
  out.farQuantileD = q.far;
  out.contextVoxels = q.count;
  unitFromQuantiles(out);
  out.derived = true;
  return out;
}

bool unitFromSeenBone(RenderMode mode) { return mode == RenderMode::Wdt || mode == RenderMode::Unweighted; }

FieldScale applyFieldScale(RenderSettings& settings, const FloatVolume& field, const Volume& volume, const Mask* body,
                           const StructureFrame& frame, const ViewRequest& request) {
  const FieldView view = fieldViewOf(settings);
  const FieldScale scale =
      fieldScale(field, volume, body, frame, boneLevels(settings.preset),
                 unitFromSeenBone(settings.preset.mode) ? &view : nullptr, request.margin, request.minRadiusMm);
  settings.distanceUnit = scale.distanceUnit * request.contextScale;
  settings.distanceOffset = scale.distanceOffset;
  return scale;
}

}  // namespace at::render
