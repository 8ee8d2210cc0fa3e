#include "render/structure_pick.h"

#include <algorithm>
#include <cmath>

namespace at::render {

PickResult pickStructure(const SceneVolumes& scene, const RenderSettings& settings, const TransferFunction2D& table,
                         double x, double y, double beyondMm) {
  // Where the ray first shows something (a structure it leaves before then is not drawn) and where
  // it turns opaque.
  const PickPair seen = pickAtTwoThresholds(scene, settings, table, x, y, kVisibleOpacity, kSeenThroughOpacity);
  const PickResult& opaque = seen.high;
  const PickResult& visible = seen.low;
  if (!scene.labels || scene.labels->empty()) return opaque;
  const LabelMap& labels = *scene.labels;
  const Geometry& g = labels.geometry;
  const Ray ray = settings.camera.rayThroughPixel(x, y, settings.width, settings.height);
  const double step = 0.5 * std::min({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]});
  const double tOpaque = opaque.hit ? dot(opaque.pointMm - ray.origin, ray.direction) : 0.0;
  const double tEnd = opaque.hit ? tOpaque + beyondMm : settings.camera.farMm();
  const double tVisible = visible.hit ? dot(visible.pointMm - ray.origin, ray.direction) : 1e30;
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
  const auto labelAt = [&](double t) -> std::uint16_t {
    const Vec3 p = ray.origin + t * ray.direction;
    if (settings.clip && !settings.clip->keeps(p)) return 0;
    const Vec3 ijk = g.patientToIndex(p);
    const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
    return g.dims.contains(i, j, k) ? labels.at(i, j, k) : std::uint16_t(0);
  };
  const auto hitAt = [&](double t, std::uint16_t label) {
    PickResult r;
    r.hit = true;
    r.label = label;
    r.pointMm = ray.origin + t * ray.direction;
    r.accumulatedOpacity = opaque.accumulatedOpacity;
    return r;
  };
  // The first labelled structure along the ray, and where the ray leaves it.
  double tFirst = -1, tLeaves = t1;
  std::uint16_t first = 0;
  for (double t = t0; t <= t1; t += step) {
    const std::uint16_t label = labelAt(t);
    if (first == 0 && label != 0) {
      first = label;
      tFirst = t;
    } else if (first != 0 && label != first) {
      tLeaves = t;
      break;
    }
  }
  if (first == 0) return opaque;
  // The first structure is drawn (the ray shows something before leaving it), or the ray shows
  // nothing behind it: it is the one pointed at (hollow structures — canals, cavities, sinuses —
  // are seen through, framed by their walls).
  // Samples within half a voxel of the structure's end blend in what lies beyond it (trilinear
  // interpolation), and the walk finds the end a step late: what shows in the structure's last voxel
  // along the ray is not taken for its own.
  const double seenDepth = std::max({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]});
  if (tVisible < tLeaves - seenDepth || !visible.hit) return hitAt(tFirst, first);
  // Else the ray passes an undrawn structure (soft tissue before bone, air before a wall) and
  // shows something behind it: when that is labelled (within a voxel of where it shows), it is the
  // one seen and pointed at; an unlabelled wall is the undrawn structure's own.
  for (double t = std::max(tVisible, tLeaves); t <= std::min(t1, tVisible + seenDepth); t += step)
    if (const std::uint16_t label = labelAt(t); label != 0 && label != first) return hitAt(t, label);
  return hitAt(tFirst, first);
}

}  // namespace at::render
