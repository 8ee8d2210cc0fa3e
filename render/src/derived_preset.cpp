#include "render/derived_preset.h"

#include "volume/body_mask.h"
#include "volume/intensity_landmarks.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace at::render {

namespace {

constexpr int kBins = 65536;  // one per int16 value

struct Histogram {
  std::vector<std::uint64_t> counts = std::vector<std::uint64_t>(kBins, 0);
  std::uint64_t total = 0;

  static int binOf(int value) { return value + 32768; }
  static double valueOf(int bin) { return double(bin - 32768); }
  // The value below which `fraction` of the voxels at or above `from` lie.
  double percentile(double fraction, int from = -32768) const {
    std::uint64_t n = 0;
    for (int b = binOf(from); b < kBins; ++b) n += counts[std::size_t(b)];
    if (n == 0) return double(from);
    const auto target = std::uint64_t(std::ceil(fraction * double(n)));
    std::uint64_t seen = 0;
    for (int b = binOf(from); b < kBins; ++b) {
      seen += counts[std::size_t(b)];
      if (seen >= std::max<std::uint64_t>(target, 1)) return valueOf(b);
    }
    return valueOf(kBins - 1);
  }
  std::uint64_t countFrom(int from) const {
    std::uint64_t n = 0;
    for (int b = binOf(from); b < kBins; ++b) n += counts[std::size_t(b)];
    return n;
  }
};

// The most populated value band of `width` in [lo, hi], and the half-width at half of its count.
struct Mode {
  double centre = 0, halfWidth = 0;
};
Mode modeIn(const Histogram& h, double lo, double hi, int width) {
  width = std::max(1, width);
  std::uint64_t best = 0;
  int bestStart = Histogram::binOf(int(lo));
  std::uint64_t window = 0;
  const int first = Histogram::binOf(int(std::floor(lo))), last = Histogram::binOf(int(std::ceil(hi)));
  for (int b = first; b <= last && b < kBins; ++b) {
    window += h.counts[std::size_t(b)];
    if (b - first >= width) window -= h.counts[std::size_t(b - width)];
    if (window > best) {
      best = window;
      bestStart = b - width + 1;
    }
  }
  Mode m;
  const int centreBin = bestStart + width / 2;
  m.centre = Histogram::valueOf(centreBin);
  // Half-width: how far the band's count stays above half its peak, in bands of `width`.
  const auto bandCount = [&](int startBin) {
    std::uint64_t n = 0;
    for (int b = std::max(0, startBin); b < std::min(kBins, startBin + width); ++b) n += h.counts[std::size_t(b)];
    return n;
  };
  int steps = 0;
  while (steps < 200 && bandCount(bestStart + (steps + 1) * width) * 2 >= best &&
         bandCount(bestStart - (steps + 1) * width) * 2 >= best)
    ++steps;
  m.halfWidth = double((steps + 1) * width);
  return m;
}

TfPoint point(double x, float r, float g, float b, float a) { return {x, {r, g, b, a}}; }

// A TF whose x must increase strictly: each point at least 1 past the previous one.
std::vector<TfPoint> increasing(std::vector<TfPoint> points) {
  for (std::size_t i = 1; i < points.size(); ++i)
    points[i].x = std::max(points[i].x, points[i - 1].x + 1.0);
  for (TfPoint& p : points) p.x = std::clamp(p.x, -32768.0, 32767.0);
  return points;
}

constexpr std::array<float, 3> kBone{0.96f, 0.93f, 0.86f};
constexpr std::array<float, 3> kOrange{1.0f, 0.5f, 0.12f};
constexpr std::array<float, 3> kGreen{0.1f, 0.85f, 0.3f};
// Lighting's context: neutral, so that the only colour on it is the structure's light (Eq. 6).
constexpr std::array<float, 3> kNeutral{0.92f, 0.92f, 0.92f};

// The bone surfaces' data TF: zero below the dense band, `peak` opacity from its median, a little
// less up to its 99th percentile (thin dense walls matter more than thick dense bone).
std::vector<TfPoint> boneTf(const IntensityLevels& l, float peak, float high) {
  const double rise = std::max(1.0, l.densePeak - l.denseLow);
  return increasing({point(l.background, 0, 0, 0, 0), point(l.denseLow - 0.25 * rise, kBone[0], kBone[1], kBone[2], 0),
                     point(l.densePeak, kBone[0], kBone[1], kBone[2], peak),
                     point(l.denseHigh, 0.98f, 0.96f, 0.9f, high),
                     point(l.denseHigh + rise, 1, 0.98f, 0.94f, high)});
}

std::vector<TfPoint> withColour(std::array<float, 3> c, std::initializer_list<std::pair<double, float>> xa) {
  std::vector<TfPoint> out;
  for (const auto& [x, a] : xa) out.push_back(point(x, c[0], c[1], c[2], a));
  return out;
}

}  // namespace

IntensityLevels summariseIntensities(const Volume& volume, IntensityScale scale) {
  Histogram h;
  for (std::int16_t v : volume.voxels) ++h.counts[std::size_t(Histogram::binOf(v))];
  h.total = volume.voxels.size();
  IntensityLevels l;
  if (h.total == 0) {
    l.reason = "empty volume";
    return l;
  }
  const double p1 = h.percentile(0.01), p99 = h.percentile(0.995);
  if (scale == IntensityScale::Unknown) {
    // Hounsfield units: air at about −1000 and soft tissue near 0.
    const Mode tissue = modeIn(h, -500, 500, 20);
    const bool hu = p1 <= -900 && std::abs(tissue.centre) <= 200;
    scale = hu ? IntensityScale::Hounsfield : IntensityScale::Plain;
    l.reason = hu ? "histogram: air at " + std::to_string(int(p1)) + " and soft tissue at " +
                        std::to_string(int(tissue.centre)) + ", read as Hounsfield units"
                  : "histogram: lowest level " + std::to_string(int(p1)) + ", not air at −1000: plain intensities";
  } else {
    l.reason = scale == IntensityScale::Hounsfield ? "Hounsfield units (intensity model)"
                                                   : "plain intensities (intensity model)";
  }
  l.scale = scale;
  double denseFrom = 0;
  if (scale == IntensityScale::Hounsfield) {
    l.background = -1000;
    l.tissue = 40;
    denseFrom = 150;
  } else {
    l.background = p1;
    const double range = std::max(1.0, p99 - p1);
    // The tissue's mode above the air: above the valley after the body's threshold
    // (volume/intensity_landmarks.h), where a scanner's second air level inside its field of view
    // (a CT stored without its rescale: 0 outside the circle, about 100 inside) no longer counts.
    const SoftTissueLandmarks landmarks = softTissueLandmarks(h.counts, int(p1));
    const double from = std::max(p1 + 0.05 * range, double(landmarks.valley));
    const Mode tissue = modeIn(h, from, std::max(from, p99), std::max(1, int(range / 256)));
    l.tissue = tissue.centre;
    denseFrom = l.tissue + std::max(4.0 * tissue.halfWidth, 0.03 * range);
  }
  const std::uint64_t dense = h.countFrom(int(std::ceil(denseFrom)));
  l.denseShare = double(dense) / double(h.total);
  if (dense * 10000 < h.total) {  // (almost) nothing dense: surfaces just above the tissue level
    const double step = std::max(1.0, denseFrom - l.tissue);
    l.denseLow = denseFrom;
    l.densePeak = denseFrom + step;
    l.denseHigh = denseFrom + 3 * step;
  } else {
    const int from = int(std::ceil(denseFrom));
    l.denseLow = h.percentile(0.10, from);
    l.densePeak = std::max(l.denseLow + 1, h.percentile(0.50, from));
    l.denseHigh = std::max(l.densePeak + 1, h.percentile(0.99, from));
  }
  return l;
}

double bodyLevel(const IntensityLevels& l) {
  return l.scale == IntensityScale::Hounsfield ? -300.0 : l.background + 0.5 * (l.tissue - l.background);
}

Mask anatomyMask(const Volume& volume, const LabelMap& labels, const IntensityLevels& levels) {
  Mask body = bodyMask(volume, bodyLevel(levels));
  if (labels.voxels.size() == body.voxels.size())
    for (std::size_t p = 0; p < body.voxels.size(); ++p)
      if (labels.voxels[p] != 0) body.voxels[p] = 1;
  return body;
}

std::size_t leaveOutNonAnatomy(Volume& volume, const LabelMap& labels, const IntensityLevels& levels) {
  const Mask body = anatomyMask(volume, labels, levels);
  const double bg = std::clamp(std::round(levels.background), -32768.0, 32767.0);
  return clearOutsideBody(volume, body, std::int16_t(bg));
}

Preset derivedPreset(const IntensityLevels& l, RenderMode mode, const std::string& structureId) {
  Preset p;
  p.mode = mode;
  p.id = structureId + "_" + toString(mode);
  p.name = structureId + " – " + toString(mode) + " (derived from the data)";
  p.structure = structureId;
  p.alpha = 1.6f;
  p.t = 0;
  p.highlightRgb = kOrange;
  p.structureOpacity = 0.95f;
  // A blurred step of height C peaks at about C/3.5 HU per voxel: the ramp spans its weaker half.
  const double contrast = std::max(1.0, l.densePeak - l.tissue);
  p.surfaceGradientHu = {float(0.06 * contrast), float(0.25 * contrast)};
  p.surfaceInterior = 0;
  if (l.scale == IntensityScale::Hounsfield) {
    p.huWindow = {-600, 2000};
  } else {
    p.huWindow = {float(l.background), float(std::max(l.background + 1, l.denseHigh))};
  }
  // Medium-opacity bone surfaces (the paper's white context): about 0.3 per voxel of surface, so an
  // edge of two or three samples covers about half of what lies behind it.
  p.dataTf = boneTf(l, 0.3f, 0.25f);
  // Context between the eye and the structure at a small fraction, so bone in front of it does not
  // veil it.
  p.contextInFront = 0.12f;
  // Full context within about one distance unit, fading out by about 4.7 units (f = 0.2), so the fade
  // shows inside the framed view and the slider t has far context to bring in.
  p.distanceTf = {point(0, 1, 1, 1, 0), point(0.2, 1, 1, 1, 0), point(0.45, 0.97f, 0.95f, 0.9f, 0.55f),
                  point(0.75, 1, 0.93f, 0.82f, 1), point(1, 1, 0.78f, 0.55f, 1)};
  switch (mode) {
    case RenderMode::Wdt:
    case RenderMode::Bare:
    case RenderMode::Unweighted:
      break;
    case RenderMode::Fuzzy:  // Eqs. 4–5: the highlight fading over the bone next to the structure
      p.t = 0.12f;
      // Full colour within x ≈ 0.3 units (n = 0.93), 0.6 at x ≈ 1.2 (n = 0.73), none beyond x ≈ 2.8
      // (n = 0.42): the median bone in view (x = kContextQuantileX = 2.6) keeps about its own
      // colour, so the gradient stays near the structure.
      p.distanceTf = withColour(kOrange, {{0, 0}, {0.42, 0}, {0.73, 0.6f}, {0.93, 1}, {1, 1}});
      break;
    case RenderMode::Outline:  // a thin band at one weighted distance on the bone around the structure
      // The bone near the structure as translucent context (κ = 0.58: 0.9 · 0.58² ≈ 0.3 per voxel of
      // surface, Algorithm 1), fading with weighted distance as in the WDT view, so the band reads on
      // it and the structure shows through even inside solid bone (a µCT of a temporal bone, whose
      // outer surface and inner walls, all drawn, made a wall in front of it); t brings in the rest,
      // t = 1 the opaque skull.
      p.t = 0;
      // The band and bone between the eye and the structure at 0.3 of their opacity: the band's
      // shell wraps the structure, and inside solid bone it and the bone near it lie in front of
      // the structure from every side; a structure on the surface (the zygomatic arch) has little
      // in front of it.
      p.contextInFront = 0.3f;
      p.dataTf = boneTf(l, 0.9f, 0.9f);
      // The band at x ≈ 0.58 (n = 0.865), 0.17 units wide (a wider or farther band, seen through the
      // translucent bone on the far side too, reads as a wall: 10 px at 160 px on the ear canal).
      p.distanceTf = {point(0, kBone[0], kBone[1], kBone[2], 0), point(0.2, kBone[0], kBone[1], kBone[2], 0),
                      point(0.45, kBone[0], kBone[1], kBone[2], 0.58f * 0.55f), point(0.75, kBone[0], kBone[1], kBone[2], 0.58f),
                      point(0.845, kBone[0], kBone[1], kBone[2], 0.58f), point(0.865, kGreen[0], kGreen[1], kGreen[2], 1),
                      point(0.885, kBone[0], kBone[1], kBone[2], 0.58f), point(1, kBone[0], kBone[1], kBone[2], 0.58f)};
      break;
    case RenderMode::Lighting:  // Eq. 6: the structure lights the bone around it
      p.t = 0.25f;
      p.dataTf = boneTf(l, 0.3f, 0.3f);
      for (TfPoint& q : p.dataTf) std::copy(kNeutral.begin(), kNeutral.end(), q.rgba.begin());
      // The bone near the light drawn fully (within x ≈ 2.5, n = 0.48), none beyond x ≈ 5 (n = 0.17).
      p.distanceTf = withColour(kNeutral, {{0, 0}, {0.17, 0}, {0.48, 1}, {1, 1}});
      // The structure is the light: drawn in its own colour, which is the colour it casts.
      // k_a = β/(α·x + 1)²: 1.8 at the structure, 0.2 at x = 0.7, 0.025 at the median bone in view
      // (x = kContextQuantileX = 2.6), so the light falls off inside the view and the far bone is
      // lit only neutrally.
      p.lightingAlpha = 2.9f;
      p.lightingBeta = 1.8f;
      break;
  }
  return p;
}

Result<Preset> presetOrDerived(const PresetLibrary& library, const std::string& structureId, RenderMode mode,
                               const IntensityLevels& levels) {
  const std::string id = structureId + "_" + toString(mode);
  std::error_code ec;
  if (std::filesystem::exists(library.dir() / (id + ".json"), ec)) return library.load(id);
  if (ec) return fail(library.dir().string() + ": cannot read the presets folder (" + ec.message() + ")");
  return derivedPreset(levels, mode, structureId);
}

}  // namespace at::render
