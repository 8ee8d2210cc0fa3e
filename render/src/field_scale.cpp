#include "render/field_scale.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "render/picture_scale.h"
#include "render/transfer_function.h"
#include "view_rays.h"

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

double drawnToX(const Preset& preset) {
  auto dist = TransferFunction1D::fromPoints(preset.distanceTf);
  if (!dist || preset.alpha <= 1.0f) return std::numeric_limits<double>::infinity();
  float peak = 0;
  for (const TfPoint& p : preset.dataTf) peak = std::max(peak, p.rgba[3]);
  // x from far to near would need the inverse of f; a scan of x in steps of 0.01 units is cheap.
  double lastDrawn = -1;
  for (double x = 0; x <= 40; x += 0.01) {
    const double k = dist->evaluate(normaliseDistance(float(x), preset.alpha))[3];
    if (peak * k * k >= kFaintOpacity) lastDrawn = x;
  }
  if (lastDrawn < 0) return 0;
  return lastDrawn >= 39.99 ? std::numeric_limits<double>::infinity() : lastDrawn + 0.01;
}

BoneLevels boneLevels(const Preset& preset) { return {denseLevel(preset), openLevel(preset), drawnToX(preset)}; }

namespace {

using detail::indexRay;
using detail::IndexRay;
using detail::voxelOn;

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
  const auto [w, h] = detail::rayGridOf(view.width, view.height, kScaleRaysPerSide);
  std::vector<std::vector<float>> rows(std::size_t(std::max(h, 0)));
  forEachRowInParallel(h, [&, w = w, h = h](int py) {
    for (int px = 0; px < w; ++px) {
      const Ray ray = view.camera.rayThroughPixel(px, py, w, h);
      // The reach's segment of the ray (|origin + t·direction − centroid| ≤ reach).
      const Vec3 oc = ray.origin - frame.centroidMm;
      const double b = dot(oc, ray.direction), c = dot(oc, oc) - reach * reach, disc = b * b - c;
      if (disc <= 0) continue;
      const double t0 = std::max(0.0, -b - std::sqrt(disc));
      const IndexRay rv = indexRay(vg, ray), rf = indexRay(fg, ray);
      // Only the part inside the volume is marched (the reach may be far larger than a µCT's
      // volume), on the same sample positions as the whole segment would have.
      double box0 = 0, box1 = 0;
      detail::boxSegment(rv, vg.dims, box0, box1);
      const double t1 = std::min(-b + std::sqrt(disc), box1);
      double tFirst = t0 + 0.5 * step;
      if (box0 > tFirst) tFirst += std::floor((box0 - tFirst) / step) * step;
      bool open = false;
      float first = 0;  // the first surface's D (0: none yet)
      for (double t = tFirst; t < t1; t += step) {
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
      if (first > 0) rows[std::size_t(py)].push_back(first);
    }
  });
  for (const auto& row : rows) d.insert(d.end(), row.begin(), row.end());
  return d;
}

// The field trilinearly at an index-space position (as the ray caster's texture reads it); +inf
// outside the grid.
float fieldAt(const FloatVolume& field, const Vec3& ijk) {
  const Dims& d = field.geometry.dims;
  const int n[3] = {d.x, d.y, d.z};
  int i0[3];
  double f[3];
  for (int a = 0; a < 3; ++a) {
    const double c = std::clamp(ijk[a], 0.0, double(n[a] - 1));
    i0[a] = std::min(int(c), std::max(0, n[a] - 2));
    f[a] = n[a] > 1 ? c - i0[a] : 0.0;
  }
  double sum = 0;
  for (int corner = 0; corner < 8; ++corner) {
    int q[3];
    double w = 1;
    for (int a = 0; a < 3; ++a) {
      const int up = (corner >> a) & 1;
      q[a] = std::min(i0[a] + up, n[a] - 1);
      w *= up ? f[a] : 1 - f[a];
    }
    if (w == 0) continue;
    const float v = field.voxels[d.index(q[0], q[1], q[2])];
    if (!std::isfinite(v)) return std::numeric_limits<float>::infinity();
    sum += w * v;
  }
  return float(sum);
}

// The nearest bone each ray of the view crosses anywhere inside the volume (the whole ray, not only
// the reach): a pixel shows context at t = 0 only where its ray crosses bone at a small x. Rays that
// meet the structure are counted apart (that pixel shows the structure).
struct RayBone {
  std::vector<float> nearest;  // the smallest D of a dense voxel on each ray that crosses bone
  std::size_t rays = 0, structureRays = 0;
};
RayBone nearestBoneOnRays(const FloatVolume& field, const Volume& volume, const Mask* body, double denseFrom,
                          const FieldView& view) {
  RayBone out;
  const Geometry& fg = field.geometry;
  const Geometry& vg = volume.geometry;
  if (view.width < 1 || view.height < 1) return out;
  const bool bodyOnGrid = body && body->geometry.dims.count() == vg.dims.count();
  // One voxel per step: a bone crossing is at least a voxel thick.
  const double step = std::min({vg.spacingMm[0], vg.spacingMm[1], vg.spacingMm[2]});
  const auto [w, h] = detail::rayGridOf(view.width, view.height, kScaleRaysPerSide);
  std::vector<RayBone> rows(std::size_t(std::max(h, 0)));
  forEachRowInParallel(h, [&, w = w, h = h](int py) {
    RayBone& row = rows[std::size_t(py)];
    for (int px = 0; px < w; ++px) {
      ++row.rays;
      const Ray ray = view.camera.rayThroughPixel(px, py, w, h);
      const IndexRay rv = indexRay(vg, ray), rf = indexRay(fg, ray);
      double t0 = 0, t1 = 0;
      detail::boxSegment(rv, vg.dims, t0, t1);
      float nearest = std::numeric_limits<float>::infinity();
      bool structure = false;
      for (double t = t0 + 0.5 * step; t < t1; t += step) {
        if (view.clip && !view.clip->keeps(ray.origin + t * ray.direction)) continue;
        int vi[3], fi[3];
        if (!voxelOn(rv, t, vg.dims, vi) || !voxelOn(rf, t, fg.dims, fi)) continue;
        const float D = field.voxels[fg.dims.index(fi[0], fi[1], fi[2])];
        if (D == 0) {
          structure = true;
          break;
        }
        const std::size_t idx = vg.dims.index(vi[0], vi[1], vi[2]);
        if (double(volume.voxels[idx]) < denseFrom) continue;
        if (bodyOnGrid && body->voxels[idx] == 0) continue;
        nearest = std::min(nearest, fieldAt(field, rf.origin + t * rf.perMm));
      }
      if (structure)
        ++row.structureRays;
      else if (std::isfinite(nearest))
        row.nearest.push_back(nearest);
    }
  });
  for (const RayBone& row : rows) {
    out.rays += row.rays;
    out.structureRays += row.structureRays;
    out.nearest.insert(out.nearest.end(), row.nearest.begin(), row.nearest.end());
  }
  return out;
}

// Caps the unit so that at t = 0 at most kMaxDrawnShare of the view's pixels (the structure's
// included) show context: the rays beyond that share have their nearest bone at x ≥ drawnToX,
// where the preset draws bone faintly. Only ever shrinks the unit.
void capByRays(FieldScale& out, RayBone rays, double drawnToX) {
  out.viewRays = rays.rays;
  if (rays.rays == 0 || rays.nearest.empty() || !std::isfinite(drawnToX) || drawnToX <= 0) return;
  out.boneRayShare = double(rays.nearest.size()) / double(rays.rays);
  std::size_t drawnNow = rays.structureRays;
  for (float D : rays.nearest) drawnNow += (D - out.distanceOffset) / out.distanceUnit < drawnToX;
  const double share = double(drawnNow) / double(rays.rays);
  // Context rays that may stay drawn: the share left after the structure's, but at least
  // kMinDrawnBoneShare of the rays that cross bone (a structure filling the view keeps some context).
  const double allowed = std::max(kMaxDrawnShare * double(rays.rays) - double(rays.structureRays),
                                  kMinDrawnBoneShare * double(rays.nearest.size()));
  if (share <= kMaxDrawnShare || allowed >= double(rays.nearest.size())) return;
  const auto kth = rays.nearest.begin() + std::ptrdiff_t(std::max(0.0, std::floor(allowed)));
  std::nth_element(rays.nearest.begin(), kth, rays.nearest.end());
  const double D = *kth;
  out.drawnLimitD = D;
  if ((D - out.distanceOffset) / out.distanceUnit >= drawnToX) return;  // already faint there
  // x = D / unit from here: the rays' D follows the anatomy, not the grid (the narrow-spread offset
  // comes from quantiles of surfaces that a coarser grid samples differently).
  out.distanceOffset = 0;
  out.distanceUnit = std::max(1e-6, D / drawnToX);
  out.cappedByRays = true;
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
  const double reach = std::max(minRadiusMm * fineVoxelScale(frame), margin * frame.radiusMm);
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
  if (view) capByRays(out, nearestBoneOnRays(field, volume, body, denseFrom, *view), levels.drawnToX);
  out.derived = true;
  return out;
}

bool unitFromSeenBone(RenderMode mode) { return mode == RenderMode::Wdt || mode == RenderMode::Unweighted; }

FieldScale applyFieldScale(RenderSettings& settings, const FloatVolume& field, const Volume& volume, const Mask* body,
                           const StructureFrame& frame, const ViewRequest& request, const PictureInputs* picture) {
  const FieldView view = fieldViewOf(settings);
  const BoneLevels levels = boneLevels(settings.preset);
  FieldScale scale = fieldScale(field, volume, body, frame, levels, unitFromSeenBone(settings.preset.mode) ? &view : nullptr,
                                request.margin, request.minRadiusMm);
  if (unitFromNeighbourBone(settings.preset.mode)) unitFromNeighbours(scale, neighbourBone(field, volume, body, levels, view), settings.preset.mode);
  if (picture && picture->labels) {
    SceneVolumes scene;
    scene.volume = &volume;
    scene.labels = picture->labels;
    scene.field = &field;
    scene.selected = picture->selected;
    scene.gradients = picture->gradients;
    scaleFromPicture(scale, scene, settings, request.contextScale);
  }
  settings.distanceUnit = scale.distanceUnit * request.contextScale;
  settings.distanceOffset = scale.distanceOffset;
  settings.lightingReach = scale.lightingReach;
  return scale;
}

}  // namespace at::render
