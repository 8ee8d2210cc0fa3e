#include "render/render_settings.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace at::render {

namespace {

float srgbToLinear(float c) { return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f); }
float linearToSrgb(float c) {
  c = std::clamp(c, 0.0f, 1.0f);
  return c <= 0.0031308f ? 12.92f * c : 1.055f * std::pow(c, 1.0f / 2.4f) - 0.055f;
}

// Trilinear sample at continuous index coordinates, clamped to the edge (GL_CLAMP_TO_EDGE);
// value(linear index) gives a voxel's value.
template <class F>
double trilinear(const Dims& d, const Vec3& ijk, F value) {
  double c[3] = {std::clamp(ijk[0], 0.0, double(d.x - 1)), std::clamp(ijk[1], 0.0, double(d.y - 1)),
                 std::clamp(ijk[2], 0.0, double(d.z - 1))};
  const int i0 = int(c[0]), j0 = int(c[1]), k0 = int(c[2]);
  const int i1 = std::min(i0 + 1, d.x - 1), j1 = std::min(j0 + 1, d.y - 1), k1 = std::min(k0 + 1, d.z - 1);
  const double fx = c[0] - i0, fy = c[1] - j0, fz = c[2] - k0;
  const auto v = [&](int i, int j, int k) { return double(value(d.index(i, j, k))); };
  const double x00 = v(i0, j0, k0) * (1 - fx) + v(i1, j0, k0) * fx;
  const double x10 = v(i0, j1, k0) * (1 - fx) + v(i1, j1, k0) * fx;
  const double x01 = v(i0, j0, k1) * (1 - fx) + v(i1, j0, k1) * fx;
  const double x11 = v(i0, j1, k1) * (1 - fx) + v(i1, j1, k1) * fx;
  return (x00 * (1 - fy) + x10 * fy) * (1 - fz) + (x01 * (1 - fy) + x11 * fy) * fz;
}

template <class T, class F>
double trilinear(const Grid<T>& g, const Vec3& ijk, F value) {
  return trilinear(g.dims(), ijk, [&](std::size_t i) { return value(g.voxels[i]); });
}

// The selected structure's mask as the GPU holds it: 1 where the label is `label`, smoothed by a
// [1 2 1]³/64 binomial (edge-clamped; a labelled voxel it would drop below 0.5 raised to 0.75),
// sampled trilinearly.
// The mask's value at voxel (i, j, k), in 64ths (0 … 64; 48 = 0.75).
int maskSixtyFourths(const LabelMap& labels, std::uint16_t label, int i, int j, int k) {
  const Dims& d = labels.dims();
  int sum = 0;
  for (int dk = -1; dk <= 1; ++dk)
    for (int dj = -1; dj <= 1; ++dj)
      for (int di = -1; di <= 1; ++di) {
        const int x = std::clamp(i + di, 0, d.x - 1), y = std::clamp(j + dj, 0, d.y - 1), z = std::clamp(k + dk, 0, d.z - 1);
        if (labels.voxels[d.index(x, y, z)] == label) sum += (2 - std::abs(di)) * (2 - std::abs(dj)) * (2 - std::abs(dk));
      }
  return sum < 32 && labels.at(i, j, k) == label ? 48 : sum;
}

double smoothedMaskAt(const LabelMap& labels, std::uint16_t label, const Vec3& ijk) {
  const Dims& d = labels.dims();
  return trilinear(d, ijk, [&](std::size_t index) {
    const int i = int(index % std::size_t(d.x)), j = int((index / std::size_t(d.x)) % std::size_t(d.y)),
              k = int(index / (std::size_t(d.x) * std::size_t(d.y)));
    return double(maskSixtyFourths(labels, label, i, j, k)) / 64.0;
  });
}

}  // namespace

double SelectedMask::at(std::size_t labelIndex) const {
  const int i = int(labelIndex % std::size_t(dims.x)), j = int((labelIndex / std::size_t(dims.x)) % std::size_t(dims.y)),
            k = int(labelIndex / (std::size_t(dims.x) * std::size_t(dims.y)));
  if (i < lo[0] || j < lo[1] || k < lo[2] || i > hi[0] || j > hi[1] || k > hi[2]) return 0;
  const std::size_t w = std::size_t(hi[0] - lo[0] + 1), h = std::size_t(hi[1] - lo[1] + 1);
  return double(sixtyFourths[(std::size_t(k - lo[2]) * h + std::size_t(j - lo[1])) * w + std::size_t(i - lo[0])]) / 64.0;
}

SelectedMask selectedMask(const LabelMap& labels, std::uint16_t label) {
  SelectedMask m;
  m.label = label;
  m.dims = labels.dims();
  const Dims& d = m.dims;
  m.lo = {d.x, d.y, d.z};
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i)
        if (labels.voxels[d.index(i, j, k)] == label) {
          m.lo = {std::min(m.lo[0], i), std::min(m.lo[1], j), std::min(m.lo[2], k)};
          m.hi = {std::max(m.hi[0], i), std::max(m.hi[1], j), std::max(m.hi[2], k)};
        }
  if (m.hi[0] < m.lo[0]) {
    m.lo = {0, 0, 0};
    m.hi = {-1, -1, -1};
    return m;  // no voxel of the label: 0 everywhere
  }
  // Grown by one voxel: a voxel next to the label has a share of it; one further has none.
  m.lo = {std::max(m.lo[0] - 1, 0), std::max(m.lo[1] - 1, 0), std::max(m.lo[2] - 1, 0)};
  m.hi = {std::min(m.hi[0] + 1, d.x - 1), std::min(m.hi[1] + 1, d.y - 1), std::min(m.hi[2] + 1, d.z - 1)};
  m.sixtyFourths.reserve(std::size_t(m.hi[0] - m.lo[0] + 1) * std::size_t(m.hi[1] - m.lo[1] + 1) *
                         std::size_t(m.hi[2] - m.lo[2] + 1));
  for (int k = m.lo[2]; k <= m.hi[2]; ++k)
    for (int j = m.lo[1]; j <= m.hi[1]; ++j)
      for (int i = m.lo[0]; i <= m.hi[0]; ++i)
        m.sixtyFourths.push_back(std::uint8_t(maskSixtyFourths(labels, label, i, j, k)));
  return m;
}

std::array<float, 3> srgbToXyz(const std::array<float, 3>& rgb) {
  const float r = srgbToLinear(rgb[0]), g = srgbToLinear(rgb[1]), b = srgbToLinear(rgb[2]);
  return {0.4124564f * r + 0.3575761f * g + 0.1804375f * b, 0.2126729f * r + 0.7151522f * g + 0.0721750f * b,
          0.0193339f * r + 0.1191920f * g + 0.9503041f * b};
}

std::array<float, 3> xyzToSrgb(const std::array<float, 3>& xyz) {
  const float x = xyz[0], y = xyz[1], z = xyz[2];
  return {linearToSrgb(3.2404542f * x - 1.5371385f * y - 0.4985314f * z),
          linearToSrgb(-0.9692660f * x + 1.8760108f * y + 0.0415560f * z),
          linearToSrgb(0.0556434f * x - 0.2040259f * y + 1.0572252f * z)};
}

TransferFunction2D shadingTable(const Preset& preset) {
  auto data = TransferFunction1D::fromPoints(preset.dataTf);
  auto dist = TransferFunction1D::fromPoints(preset.distanceTf);
  // Presets are validated on load; a hand-built invalid one falls back to the defaults.
  if (!data) data = TransferFunction1D::fromPoints(Preset{}.dataTf);
  if (!dist) dist = TransferFunction1D::fromPoints(Preset{}.distanceTf);
  TransferFunction2D table = buildTransferFunction2D(*data, *dist, preset.t);
  if (preset.mode != RenderMode::Fuzzy) return table;
  // Eqs. 4–5 replace Algorithm 1's colours and opacities.
  const int n = table.dataSize, m = table.distanceSize;
  for (int j = 0; j < m; ++j) {
    const Rgba kh = dist->evaluate(double(j) / double(m - 1));
    const auto xyzH = srgbToXyz({kh[0], kh[1], kh[2]});
    const float w = kh[3];
    for (int i = 0; i < n; ++i) {
      const Rgba kd = data->evaluate(table.dataMin + (table.dataMax - table.dataMin) * double(i) / double(n - 1));
      const auto xyzD = srgbToXyz({kd[0], kd[1], kd[2]});
      std::array<float, 3> mix;
      for (int c = 0; c < 3; ++c) mix[c] = xyzD[c] * (1 - w) + xyzH[c] * w;
      const auto rgb = xyzToSrgb(mix);
      Rgba& o = table.rgba[std::size_t(i) + std::size_t(n) * std::size_t(j)];
      o = {rgb[0], rgb[1], rgb[2], preset.t * kd[3] + (kd[3] - preset.t * kd[3]) * w};
    }
  }
  return table;
}

bool sameShadingTable(const Preset& a, const Preset& b) {
  return a.dataTf == b.dataTf && a.distanceTf == b.distanceTf && a.t == b.t &&
         (a.mode == RenderMode::Fuzzy) == (b.mode == RenderMode::Fuzzy);
}

const TransferFunction2D& ShadingTableCache::tableFor(const Preset& preset) {
  if (!preset_ || !sameShadingTable(*preset_, preset)) {
    table_ = shadingTable(preset);
    preset_ = preset;
  }
  return table_;
}

double effectiveStepMm(const Geometry& g, const RenderSettings& s) {
  if (s.stepMm > 0) return s.stepMm;
  return kDefaultStepVoxels * std::min({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]});
}

double effectiveOpacityRefMm(const Geometry& g, const RenderSettings& s) {
  if (s.opacityRefMm > 0) return s.opacityRefMm;
  return std::min({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]});
}

float outlineBandN(const Preset& preset) {
  if (preset.mode != RenderMode::Outline || preset.distanceTf.empty()) return -1.0f;
  const TfPoint* best = &preset.distanceTf.front();
  for (const TfPoint& q : preset.distanceTf)
    if (q.rgba[3] > best->rgba[3]) best = &q;
  return float(best->x);
}

float surfaceFactor(const Preset& p, float strength) {
  const float lo = p.surfaceGradientHu[0], hi = p.surfaceGradientHu[1];
  float ramp = 1;
  if (hi > lo) {
    const float x = std::clamp((strength - lo) / (hi - lo), 0.0f, 1.0f);
    ramp = x * x * (3 - 2 * x);
  } else if (strength < lo) {
    ramp = 0;
  }
  return p.surfaceInterior + (1 - p.surfaceInterior) * ramp;
}

float correctedOpacity(float alpha, double stepMm, double refMm) {
  return float(1.0 - std::pow(1.0 - std::clamp(double(alpha), 0.0, 0.999999), stepMm / refMm));
}

namespace {

// A sample the ray caster composites: where it lies and the opacity it adds (before compositing);
// `structure`: the selected structure's surface (drawn once, where the ray enters it).
struct MarchedSample {
  Vec3 pointMm;
  Vec3 ijk;  // on the volume's grid
  double opacity;
  bool structure;
  std::array<float, 3> rgb{};  // unshaded: the table's colour (lighting: times k_a, as the ray caster)
};

// Beyond this accumulated opacity nothing behind shows.
constexpr double kOpaque = 0.995;

// The ray caster's key light (volume_renderer.cpp sets it, ray_shaders.cpp shades with it): from the
// viewer, a little above and to the left; two-sided Phong with a specular of power 20.
Vec3 keyLightDirection(const Camera& camera) {
  const Vec3 right = cross(camera.forward(), camera.up());
  const Vec3 toLight = -1.0 * camera.forward() + 0.7 * camera.up() - 0.45 * right;
  return (1.0 / norm(toLight)) * toLight;
}
std::array<double, 3> keyLight(const std::array<double, 3>& rgb, const Vec3& nrm, const Vec3& viewDir, const Vec3& light) {
  if (dot(nrm, nrm) < 1e-6) return {0.75 * rgb[0], 0.75 * rgb[1], 0.75 * rgb[2]};
  const double ndl = std::fabs(dot(nrm, light));
  const Vec3 h0 = light - viewDir;
  const Vec3 h = (1.0 / std::max(1e-12, norm(h0))) * h0;
  const double spec = std::pow(std::fabs(dot(nrm, h)), 20);
  std::array<double, 3> out;
  for (std::size_t k = 0; k < 3; ++k) out[k] = rgb[k] * (0.18 + 0.82 * ndl) + 0.25 * spec;
  return out;
}

// Walks the ray through pixel (x, y) front to back as the ray caster does (without jitter), giving
// `visit` (bool(const MarchedSample&)) each sample that adds opacity; stops when `visit` returns
// false or the ray leaves the volume. The samples' colours are worked out only with `colour` (the
// pickers need opacity alone).
template <class Visit>
void marchPixel(const SceneVolumes& scene, const RenderSettings& s, const TransferFunction2D& table, double x, double y,
                const Visit& visit, bool colour = false) {
  if (!scene.volume || scene.volume->empty()) return;
  const Geometry& g = scene.volume->geometry;
  const Ray ray = s.camera.rayThroughPixel(x, y, s.width, s.height);
  // Intersect with the volume's box in index space (voxel centres at integers, box ±0.5).
  const Vec3 o = g.patientToIndex(ray.origin);
  const Vec3 e = g.patientToIndex(ray.origin + ray.direction);
  const Vec3 dirIdx = e - o;  // index units per mm
  double t0 = 0, t1 = 1e30;
  const double hi[3] = {g.dims.x - 0.5, g.dims.y - 0.5, g.dims.z - 0.5};
  for (int a = 0; a < 3; ++a) {
    if (std::fabs(dirIdx[a]) < 1e-12) {
      if (o[a] < -0.5 || o[a] > hi[a]) return;
      continue;
    }
    double ta = (-0.5 - o[a]) / dirIdx[a], tb = (hi[a] - o[a]) / dirIdx[a];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  if (!(t0 < t1)) return;
  const double step = effectiveStepMm(g, s);
  const double refMm = effectiveOpacityRefMm(g, s);
  const bool bare = s.preset.mode == RenderMode::Bare;
  const bool structure = scene.labels && scene.selected != 0;
  const Vec3 lightDir = keyLightDirection(s.camera);
  const float structureAlpha = bare ? 1.0f : s.preset.structureOpacity;
  const float alphaF = s.preset.alpha;
  const float bandN = outlineBandN(s.preset);
  const Geometry* fg = scene.field ? &scene.field->geometry : nullptr;
  double prevMask = 0;
  const SelectedMask* known = scene.selectedMask && scene.selectedMask->label == scene.selected &&
                                      scene.selectedMask->dims == g.dims
                                  ? scene.selectedMask
                                  : nullptr;
  const auto maskAt = [&](const Vec3& ijk) {
    if (known) return trilinear(g.dims, ijk, [&](std::size_t index) { return known->at(index); });
    return smoothedMaskAt(*scene.labels, scene.selected, ijk);
  };
  // Where the ray first enters the structure: context in front of it counts at contextInFront of
  // its opacity (as the ray caster draws it; it marches at twice the step).
  double frontT = -1e30;
  if (structure && !bare && s.preset.contextInFront < 1)
    for (double tm = t0; tm < t1; tm += 2 * step) {
      const Vec3 p = ray.origin + tm * ray.direction;
      if (s.clip && !s.clip->keeps(p)) continue;
      if (maskAt(g.patientToIndex(p)) >= 0.5) {
        frontT = tm;
        break;
      }
    }
  for (double tm = t0 + 0.5 * step; tm < t1; tm += step) {
    const Vec3 p = ray.origin + tm * ray.direction;
    if (s.clip && !s.clip->keeps(p)) {
      prevMask = 0;
      continue;
    }
    const Vec3 ijk = g.patientToIndex(p);
    const double m = structure ? maskAt(ijk) : 0.0;
    if (m >= 0.5) {
      if (prevMask < 0.5 && !visit({p, ijk, structureAlpha, true, s.preset.highlightRgb})) return;
      prevMask = m;
      continue;
    }
    prevMask = m;
    if (bare || m > kMaskHalo) continue;
    const double hu = trilinear(*scene.volume, ijk, [](std::int16_t v) { return double(v); });
    float n = 0;
    if (fg) {
      const double d = trilinear(*scene.field, fg->patientToIndex(p), [](float v) { return std::isinf(v) ? 1e30 : double(v); });
      n = normaliseDistance(float(std::max(0.0, d - s.distanceOffset) / s.distanceUnit), alphaF);
      if (bandN >= 0) {  // as the ray caster: the n over this step nearest the outline's band
        const auto nAt = [&](double at) {
          const double da = trilinear(*scene.field, fg->patientToIndex(ray.origin + at * ray.direction),
                                      [](float v) { return std::isinf(v) ? 1e30 : double(v); });
          return normaliseDistance(float(std::max(0.0, da - s.distanceOffset) / s.distanceUnit), alphaF);
        };
        const float na = nAt(tm - 0.5 * step), nb = nAt(tm + 0.5 * step);
        n = std::clamp(bandN, std::min(na, nb), std::max(na, nb));
      }
    }
    float surface = 1;
    double gc[3] = {0, 0, 0};
    if (scene.gradients && !scene.gradients->empty()) {
      for (std::size_t c = 0; c < 3; ++c)
        gc[c] = trilinear(g.dims, ijk, [&](std::size_t i) { return double(scene.gradients->texels[i][c + 1]) / 32767.0; });
      surface = surfaceFactor(s.preset, GradientVolume::strengthOf(float(gc[0]), float(gc[1]), float(gc[2])));
    }
    const Rgba c = table.lookup(hu, n);
    const float front = tm < frontT ? s.preset.contextInFront : 1.0f;
    const float ac = c[3] > 0 ? correctedOpacity(c[3], step, refMm) * surface * front : 0.0f;
    std::array<float, 3> rgb{c[0], c[1], c[2]};
    if (colour && s.preset.mode == RenderMode::Lighting && fg && ac > 0) {  // Eq. 6, as the ray caster
      const double d = trilinear(*scene.field, fg->patientToIndex(p), [](float v) { return std::isinf(v) ? 1e30 : double(v); });
      const double x = std::min(std::max(d - s.distanceOffset, 0.0), 1e6) * double(s.preset.lightingAlpha) /
                       (s.distanceUnit * s.lightingReach);
      const double ka = double(s.preset.lightingBeta) / ((x + 1) * (x + 1));
      std::array<double, 3> neutral{0.25 * rgb[0], 0.25 * rgb[1], 0.25 * rgb[2]};  // unshaded
      if (s.shading) {  // 0.2 of the key light's Phong, as the shaded ray caster
        const double len = std::sqrt(gc[0] * gc[0] + gc[1] * gc[1] + gc[2] * gc[2]);
        const Vec3 nrm = len * GradientVolume::kMaxHuPerVoxel > 1e-3 ? Vec3{gc[0] / len, gc[1] / len, gc[2] / len} : Vec3{0, 0, 0};
        const std::array<double, 3> lit = keyLight({rgb[0], rgb[1], rgb[2]}, nrm, ray.direction, lightDir);
        for (std::size_t k = 0; k < 3; ++k) neutral[k] = 0.2 * lit[k];
      }
      double top = 1;
      std::array<double, 3> out;
      for (std::size_t k = 0; k < 3; ++k) top = std::max(top, out[k] = rgb[k] * ka * s.preset.highlightRgb[k] + neutral[k]);
      for (std::size_t k = 0; k < 3; ++k) rgb[k] = float(out[k] / top);
    }
    if (!visit({p, ijk, double(ac), false, rgb})) return;
  }
}

}  // namespace

PickPair pickAtTwoThresholds(const SceneVolumes& scene, const RenderSettings& s, const TransferFunction2D& table,
                             double x, double y, double low, double high) {
  PickPair out;
  double accumulated = 0;
  const auto hitAt = [&](const MarchedSample& sample, PickResult& result) {
    result.hit = true;
    result.pointMm = sample.pointMm;
    result.accumulatedOpacity = accumulated;
    if (sample.structure) {
      result.label = scene.selected;
    } else if (scene.labels) {
      const Vec3& ijk = sample.ijk;
      const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
      if (scene.volume->geometry.dims.contains(i, j, k)) result.label = scene.labels->at(i, j, k);
    }
  };
  marchPixel(scene, s, table, x, y, [&](const MarchedSample& sample) {
    accumulated += (1 - accumulated) * sample.opacity;
    if (!out.low.hit && accumulated >= low) hitAt(sample, out.low);
    if (accumulated < high) return true;
    hitAt(sample, out.high);
    return false;
  });
  if (!out.low.hit) out.low.accumulatedOpacity = accumulated;
  if (!out.high.hit) out.high.accumulatedOpacity = accumulated;
  return out;
}

PickResult pick(const SceneVolumes& scene, const RenderSettings& s, const TransferFunction2D& table, double x,
                double y, double threshold) {
  return pickAtTwoThresholds(scene, s, table, x, y, threshold, threshold).high;
}

double contextOpacity(const SceneVolumes& scene, const RenderSettings& settings, const TransferFunction2D& table,
                      double x, double y) {
  double accumulated = 0, context = 0;
  marchPixel(scene, settings, table, x, y, [&](const MarchedSample& sample) {
    const double added = (1 - accumulated) * sample.opacity;
    accumulated += added;
    if (!sample.structure) context += added;
    return accumulated < kOpaque;
  });
  return context;
}

CompositedPixel compositePixel(const SceneVolumes& scene, const RenderSettings& settings, const TransferFunction2D& table,
                               double x, double y) {
  CompositedPixel out;
  marchPixel(scene, settings, table, x, y, [&](const MarchedSample& sample) {
    const double added = (1 - out.alpha) * sample.opacity;
    for (std::size_t c = 0; c < 3; ++c) out.rgb[c] += added * std::clamp(double(sample.rgb[c]), 0.0, 1.0);
    out.alpha += added;
    if (sample.structure) out.structureAlpha += added;
    return out.alpha < kOpaque;
  }, true);
  return out;
}

}  // namespace at::render
