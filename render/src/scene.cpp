#include "render/scene.h"

#include <algorithm>
#include <cmath>

namespace at::render {

Result<StructureFrame> structureFrame(const LabelMap& labels, std::uint16_t label) {
  const Dims& d = labels.geometry.dims;
  return structureFrame(labels, label, {0, 0, 0, d.x, d.y, d.z});
}

Result<StructureFrame> structureFrame(const LabelMap& labels, std::uint16_t label, const std::array<int, 6>& box) {
  const Geometry& g = labels.geometry;
  const Dims& d = g.dims;
  const int x0 = std::max(0, box[0]), y0 = std::max(0, box[1]), z0 = std::max(0, box[2]);
  const int x1 = std::min(d.x, box[3]), y1 = std::min(d.y, box[4]), z1 = std::min(d.z, box[5]);
  StructureFrame f;
  f.voxelBox = {x1, y1, z1, x0, y0, z0};  // grows to the voxels found
  double s[3] = {0, 0, 0};
  for (int k = z0; k < z1; ++k)
    for (int j = y0; j < y1; ++j)
      for (int i = x0; i < x1; ++i)
        if (labels.voxels[d.index(i, j, k)] == label) {
          s[0] += i;
          s[1] += j;
          s[2] += k;
          ++f.voxelCount;
          const int at[3] = {i, j, k};
          for (std::size_t a = 0; a < 3; ++a) {
            f.voxelBox[a] = std::min(f.voxelBox[a], at[a]);
            f.voxelBox[a + 3] = std::max(f.voxelBox[a + 3], at[a] + 1);
          }
        }
  if (f.voxelCount == 0) return fail("structure label " + std::to_string(label) + " has no voxels");
  const double n = double(f.voxelCount);
  const Vec3 cIdx{s[0] / n, s[1] / n, s[2] / n};
  f.centroidMm = g.indexToPatient(cIdx);
  f.volumeMm3 = n * g.spacingMm[0] * g.spacingMm[1] * g.spacingMm[2];
  f.voxelMm = std::max({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]});
  const std::size_t every = (f.voxelCount + kMaxFramePoints - 1) / kMaxFramePoints;
  double r2 = 0, nearest2 = 1e300;
  std::size_t seen = 0;
  const std::array<int, 6>& b = f.voxelBox;  // the second pass reads only the structure's own box
  for (int k = b[2]; k < b[5]; ++k)
    for (int j = b[1]; j < b[4]; ++j)
      for (int i = b[0]; i < b[3]; ++i)
        if (labels.voxels[d.index(i, j, k)] == label) {
          const Vec3 p = g.indexToPatient({double(i), double(j), double(k)});
          const double q2 = dot(p - f.centroidMm, p - f.centroidMm);
          r2 = std::max(r2, q2);
          if (q2 < nearest2) {
            nearest2 = q2;
            f.anchorMm = p;
          }
          if (seen++ % every == 0) f.pointsMm.push_back(p);
        }
  f.radiusMm = std::sqrt(r2);
  return f;
}

StructureFrame unionFrame(const StructureFrame& a, const StructureFrame& b) {
  StructureFrame u;
  const double wa = std::max(a.volumeMm3, 1e-9), wb = std::max(b.volumeMm3, 1e-9);
  u.centroidMm = (1.0 / (wa + wb)) * (wa * a.centroidMm + wb * b.centroidMm);
  u.anchorMm = a.anchorMm;
  const Vec3 da = a.centroidMm - u.centroidMm, db = b.centroidMm - u.centroidMm;
  u.radiusMm = std::max(std::sqrt(dot(da, da)) + a.radiusMm, std::sqrt(dot(db, db)) + b.radiusMm);
  u.voxelCount = a.voxelCount + b.voxelCount;
  u.volumeMm3 = a.volumeMm3 + b.volumeMm3;
  u.voxelMm = std::max(a.voxelMm, b.voxelMm);
  u.pointsMm = a.pointsMm;
  u.pointsMm.insert(u.pointsMm.end(), b.pointsMm.begin(), b.pointsMm.end());
  return u;
}

double contextRadiusMm(const StructureFrame& f) {
  const double equivalent = std::cbrt(3.0 * f.volumeMm3 / (4.0 * 3.14159265358979323846));
  return std::sqrt(equivalent * std::max(f.radiusMm, equivalent));
}

double fineVoxelScale(const StructureFrame& f) { return at::fineVoxelScale(f.voxelMm); }

double distanceUnitFor(const StructureFrame& f, double scale) {
  return std::clamp(scale * contextRadiusMm(f) / kReferenceContextMm, 0.4 * fineVoxelScale(f), 40.0);
}

Camera frameCamera(const StructureFrame& f, NamedView view, double aspect, double margin, double minHalfHeightMm) {
  return frameCamera(f, Camera::named(view, f.centroidMm, std::max(f.radiusMm, minHalfHeightMm * fineVoxelScale(f))),
                     aspect, margin, minHalfHeightMm);
}

double shareInView(const StructureFrame& f, const Camera& camera, int width, int height) {
  const std::vector<Vec3> centre{f.centroidMm};
  const std::vector<Vec3>& points = f.pointsMm.empty() ? centre : f.pointsMm;
  std::size_t inside = 0;
  for (const Vec3& p : points)
    if (const auto px = camera.project(p, width, height))
      inside += (*px)[0] >= 0 && (*px)[0] <= width && (*px)[1] >= 0 && (*px)[1] <= height;
  return double(inside) / double(points.size());
}

Camera frameCamera(const StructureFrame& f, const Camera& orientation, double aspect, double margin, double minHalfHeightMm) {
  Camera c = orientation;
  const Vec3 right = cross(c.forward(), c.up());
  // The extent in the view plane (voxel centres, widened by half a voxel).
  double lo[2] = {1e30, 1e30}, hi[2] = {-1e30, -1e30};
  const std::vector<Vec3> centre{f.centroidMm};
  const std::vector<Vec3>& points = f.pointsMm.empty() ? centre : f.pointsMm;
  for (const Vec3& p : points) {
    const Vec3 q = p - f.centroidMm;
    const double xy[2] = {dot(q, right), dot(q, c.up())};
    for (int a = 0; a < 2; ++a) {
      lo[a] = std::min(lo[a], xy[a]);
      hi[a] = std::max(hi[a], xy[a]);
    }
  }
  const double cx = 0.5 * (lo[0] + hi[0]), cy = 0.5 * (lo[1] + hi[1]);
  c.target = f.centroidMm + cx * right + cy * c.up();
  // Distance from the eye to the target plane such that every point, widened by the margin about
  // the centre, lies inside the frustum: |x|·margin ≤ (d + z)·tan·aspect and |y|·margin ≤ (d + z)·tan.
  const double tanHalf = std::tan(c.fovYDeg * 3.14159265358979323846 / 360.0);
  const double pad = 0.5 * f.voxelMm;
  double distance = minHalfHeightMm * fineVoxelScale(f) / tanHalf;
  for (const Vec3& p : points) {
    const Vec3 q = p - c.target;
    const double x = std::fabs(dot(q, right)) + pad, y = std::fabs(dot(q, c.up())) + pad, z = dot(q, c.forward());
    distance = std::max({distance, margin * y / tanHalf - z, margin * x / (tanHalf * aspect) - z});
  }
  c.distanceMm = distance;
  return c;
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
  const auto named = parseNamedView(view);
  if (!named)
    return fail("unknown view '" + view +
                "' (expected anterior, posterior, lateral_left, lateral_right, superior or inferior)");
  s.camera = frameCamera(frame, *named, double(request.width) / double(request.height), request.margin,
                         request.minRadiusMm);
  s.distanceUnit = distanceUnitFor(frame, request.contextScale);
  const auto clip = request.clip ? request.clip : preset.clip;
  if (clip) {
    auto plane = ClipPlane::fromCoefficients((*clip)[0], (*clip)[1], (*clip)[2], (*clip)[3]);
    if (!plane) return tl::unexpected(plane.error());
    s.clip = *plane;
  }
  return s;
}

}  // namespace at::render
