#include "render/structure_pick.h"

#include <algorithm>
#include <cmath>

namespace at::render {

PickResult pickStructure(const SceneVolumes& scene, const RenderSettings& settings, const TransferFunction2D& table,
                         double x, double y, double beyondMm) {
  PickResult opaque = pick(scene, settings, table, x, y, kSeenThroughOpacity);
  if (!scene.labels || scene.labels->empty()) return opaque;
  const LabelMap& labels = *scene.labels;
  const Geometry& g = labels.geometry;
  const Ray ray = settings.camera.rayThroughPixel(x, y, settings.width, settings.height);
  const double step = 0.5 * std::min({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]});
  const double tEnd = opaque.hit ? dot(opaque.pointMm - ray.origin, ray.direction) + beyondMm : settings.camera.farMm();
  // Only the part of the ray inside the grid's box is walked.
  const Vec3 lo = g.indexToPatient({-0.5, -0.5, -0.5});
  const Vec3 hi = g.indexToPatient({g.dims.x - 0.5, g.dims.y - 0.5, g.dims.z - 0.5});
  double t0 = std::max(0.0, settings.camera.nearMm()), t1 = tEnd;
  for (std::size_t a = 0; a < 3; ++a) {
    const double bmin = std::min(lo[a], hi[a]), bmax = std::max(lo[a], hi[a]);
    if (std::abs(ray.direction[a]) < 1e-12) {
      if (ray.origin[a] < bmin || ray.origin[a] > bmax) return opaque;
      continue;
    }
    double ta = (bmin - ray.origin[a]) / ray.direction[a], tb = (bmax - ray.origin[a]) / ray.direction[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  for (double t = t0; t <= t1; t += step) {
    const Vec3 p = ray.origin + t * ray.direction;
    if (settings.clip && !settings.clip->keeps(p)) continue;
    const Vec3 ijk = g.patientToIndex(p);
    const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
    if (!g.dims.contains(i, j, k)) continue;
    const std::uint16_t label = labels.at(i, j, k);
    if (label != 0) {
      PickResult r;
      r.hit = true;
      r.label = label;
      r.pointMm = p;
      r.accumulatedOpacity = opaque.accumulatedOpacity;
      return r;
    }
  }
  return opaque;
}

}  // namespace at::render
