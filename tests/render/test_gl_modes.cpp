// Semantic image tests of the paper's modes on the analytic scenes of render_scenes.h.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>

#include "render/scene.h"
#include "render_fixture.h"
#include "render_scenes.h"

using namespace at;
using namespace at::render;

namespace {

constexpr int kSize = 96;

// A context preset for the tests: soft tissue faint, bone whiter and denser; the distance TF
// colours and reveals what is near the structure.
Preset contextPreset(RenderMode mode, float t) {
  Preset p;
  p.mode = mode;
  p.t = t;
  p.dataTf = {{-1000, {0, 0, 0, 0}}, {-100, {0, 0, 0, 0}}, {20, {0.8f, 0.55f, 0.45f, 0.06f}},
              {300, {0.85f, 0.7f, 0.6f, 0.1f}}, {1200, {0.95f, 0.92f, 0.85f, 0.5f}}, {2000, {1, 1, 1, 0.7f}}};
  p.distanceTf = {{0, {1, 1, 1, 0}}, {0.4f, {1, 0.8f, 0.5f, 0.3f}}, {1, {1, 0.45f, 0.1f, 1}}};
  p.alpha = 1.6f;
  // Algorithm 1 as the paper states it: no surface ramp (these scenes' context is soft tissue).
  p.surfaceGradientHu = {0, 0};
  p.surfaceInterior = 1;
  return p;
}

struct View {
  RenderSettings settings;
  double cx = 0, cy = 0;   // projected centre of the structure
  double rPx = 0;          // projected radius of the structure
};

View viewOf(const Preset& preset, NamedView named, const Vec3& centre, double radiusMm, double structureRadiusMm) {
  View v;
  v.settings.preset = preset;
  v.settings.width = v.settings.height = kSize;
  v.settings.jitter = false;
  v.settings.opacityRefMm = 0.25;
  v.settings.camera = Camera::named(named, centre, radiusMm);
  const auto c = v.settings.camera.project(centre, kSize, kSize);
  const auto e = v.settings.camera.project(centre + structureRadiusMm * v.settings.camera.up(), kSize, kSize);
  v.cx = (*c)[0];
  v.cy = (*c)[1];
  v.rPx = std::hypot((*e)[0] - v.cx, (*e)[1] - v.cy);
  return v;
}

// Mean of channel `ch` (0..3) over pixels whose distance from (cx, cy) lies in [r0, r1); also the
// share of those pixels above `above`.
struct RegionStats {
  double mean = 0, shareAbove = 0;
  int count = 0;
};
RegionStats region(const RgbaImage& img, double cx, double cy, double r0, double r1, int ch, int above = 20) {
  RegionStats s;
  int hits = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const double r = std::hypot(x - cx, y - cy);
      if (r < r0 || r >= r1) continue;
      const int v = ch < 3 ? img.pixel(x, y)[std::size_t(ch)] * img.pixel(x, y)[3] / 255 : img.pixel(x, y)[3];
      s.mean += v;
      hits += v > above;
      ++s.count;
    }
  if (s.count) {
    s.mean /= s.count;
    s.shareAbove = double(hits) / s.count;
  }
  return s;
}

double luminance(const RgbaImage& img, double cx, double cy, double r0, double r1) {
  return 0.2126 * region(img, cx, cy, r0, r1, 0).mean + 0.7152 * region(img, cx, cy, r0, r1, 1).mean +
         0.0722 * region(img, cx, cy, r0, r1, 2).mean;
}

RgbaImage renderScene(gl::VolumeRenderer& gl, const test::Scene& scene, const FloatVolume& field,
                      std::uint16_t selected, const RenderSettings& s) {
  REQUIRE(gl.setVolume(scene.dataset.volume, scene.dataset.labels));
  REQUIRE(gl.setField(field));
  gl.setSelected(selected);
  auto img = gl.render(s);
  REQUIRE_MESSAGE(img, img.error().message);
  return *img;
}

}  // namespace

TEST_CASE("WDT mode shows context around the structure that bare mode leaves empty") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  const auto& scene = test::chambersScene();
  View v = viewOf(contextPreset(RenderMode::Wdt, 0.0f), NamedView::Anterior, {0, 0, 0}, 9, 2);
  const RgbaImage wdt = renderScene(*gl, scene, scene.weighted, 1, v.settings);
  v.settings.preset.mode = RenderMode::Bare;
  const RgbaImage bare = renderScene(*gl, scene, scene.weighted, 1, v.settings);
  const auto wdtRing = region(wdt, v.cx, v.cy, 1.3 * v.rPx, 2.0 * v.rPx, 3);
  const auto bareRing = region(bare, v.cx, v.cy, 1.3 * v.rPx, 2.0 * v.rPx, 3);
  INFO("structure radius " << v.rPx << " px; wdt ring alpha " << wdtRing.mean << ", bare " << bareRing.mean);
  CHECK(wdtRing.count > 50);
  CHECK(wdtRing.shareAbove > 0.9);
  CHECK(bareRing.mean == 0.0);
  // The structure itself is drawn in both.
  CHECK(region(bare, v.cx, v.cy, 0, 0.5 * v.rPx, 3).shareAbove == 1.0);
  CHECK(region(wdt, v.cx, v.cy, 0, 0.5 * v.rPx, 3).shareAbove == 1.0);
}

TEST_CASE("Non-weighted distance differs from WDT where dense bone lies between the structure and a neighbour") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  const auto& scene = test::chambersScene();
  View v = viewOf(contextPreset(RenderMode::Wdt, 0.0f), NamedView::Anterior, {0, 0, 0}, 11, 2);
  const auto left = v.settings.camera.project({-7, 0, 0}, kSize, kSize);   // N−: no bone in between
  const auto right = v.settings.camera.project({7, 0, 0}, kSize, kSize);   // N+: behind the wall
  REQUIRE(left);
  REQUIRE(right);
  REQUIRE((*right)[0] > (*left)[0]);  // anterior view: the patient's left (+x) on the image's right
  const RgbaImage wdt = renderScene(*gl, scene, scene.weighted, 1, v.settings);
  v.settings.preset.mode = RenderMode::Unweighted;
  const RgbaImage unw = renderScene(*gl, scene, scene.uniform, 1, v.settings);
  const auto mean = [&](const RgbaImage& img, const std::array<double, 2>& c) {
    return region(img, c[0], c[1], 0, v.rPx, 3).mean;
  };
  const double wdtOpen = mean(wdt, *left), wdtWalled = mean(wdt, *right);
  const double unwOpen = mean(unw, *left), unwWalled = mean(unw, *right);
  INFO("wdt: open side " << wdtOpen << ", behind bone " << wdtWalled << "; unweighted: " << unwOpen << ", "
                         << unwWalled);
  CHECK(wdtOpen - wdtWalled > 15);
  CHECK(std::fabs(unwOpen - unwWalled) < 0.3 * (wdtOpen - wdtWalled));
}

TEST_CASE("Raising t from 0 to 1 adds context monotonically") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  const auto& scene = test::chambersScene();
  View v = viewOf(contextPreset(RenderMode::Wdt, 0.0f), NamedView::Anterior, {0, 0, 0}, 11, 2);
  REQUIRE(gl->setVolume(scene.dataset.volume, scene.dataset.labels));
  REQUIRE(gl->setField(scene.weighted));
  gl->setSelected(1);
  double previous = -1;
  for (float t : {0.0f, 0.25f, 0.5f, 0.75f, 1.0f}) {
    v.settings.preset.t = t;
    auto img = gl->render(v.settings);
    REQUIRE(img);
    const double total = region(*img, 0, 0, 0, 1e9, 3).mean;
    INFO("t = " << t << ": mean alpha " << total);
    CHECK(total > previous + 1);
    previous = total;
  }
}

TEST_CASE("Outline mode draws a ring around the structure's projection") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  const auto& scene = test::surfaceScene();
  // Opaque bone in its own colour, a green band at a middle distance: on the bone surface the band
  // is a ring around the structure.
  Preset p;
  p.mode = RenderMode::Outline;
  p.t = 1;
  p.dataTf = {{-1000, {0, 0, 0, 0}}, {300, {0.9f, 0.9f, 0.85f, 0}}, {1000, {0.9f, 0.9f, 0.85f, 0.9f}}};
  p.distanceTf = {{0, {0, 1, 0, 0}}, {0.4, {0, 1, 0, 0}}, {0.6, {0, 1, 0, 1}}, {0.8, {0, 1, 0, 0}},
                  {1, {0, 1, 0, 0}}};
  View v = viewOf(p, NamedView::Superior, {0, 0, 0}, 9, 1.5);
  v.settings.shading = false;
  const RgbaImage img = renderScene(*gl, scene, scene.weighted, 1, v.settings);
  const auto green = [&](int x, int y) {
    const auto px = img.pixel(x, y);
    return double(px[1]) - 0.5 * (double(px[0]) + double(px[2]));
  };
  // Radial profile of greenness around the structure's projected centre.
  std::vector<double> profile;
  for (int r = 0; r + 1 < kSize / 2; ++r) {
    double sum = 0;
    int n = 0;
    for (int y = 0; y < kSize; ++y)
      for (int x = 0; x < kSize; ++x) {
        const double d = std::hypot(x - v.cx, y - v.cy);
        if (d >= r && d < r + 1) {
          sum += green(x, y);
          ++n;
        }
      }
    profile.push_back(n ? sum / n : 0);
  }
  const auto peak = std::max_element(profile.begin(), profile.end());
  const double peakR = double(peak - profile.begin());
  INFO("peak greenness " << *peak << " at " << peakR << " px; structure radius " << v.rPx << " px");
  CHECK(*peak > 60);
  CHECK(peakR > 1.5 * v.rPx);                      // outside the structure
  CHECK(profile[0] < 0.3 * *peak);                 // the structure itself is not green
  CHECK(profile.back() < 0.3 * *peak);             // nor is bone far away
  // A ring, not an arc: every direction around the centre crosses it.
  int directions = 0;
  for (int a = 0; a < 16; ++a) {
    const double ang = a * 3.14159265358979 / 8;
    const int x = int(std::lround(v.cx + peakR * std::cos(ang))), y = int(std::lround(v.cy + peakR * std::sin(ang)));
    double best = -255;
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) best = std::max(best, green(x + dx, y + dy));
    directions += best > 0.5 * *peak;
  }
  CHECK(directions == 16);
}

TEST_CASE("Distance lighting is brighter near the structure than far from it") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  const auto& scene = test::chambersScene();
  Preset p = contextPreset(RenderMode::Lighting, 1.0f);
  p.lightingAlpha = 0.6f;
  p.lightingBeta = 1.0f;
  p.highlightRgb = {1, 0.9f, 0.7f};
  View v = viewOf(p, NamedView::Anterior, {0, 0, 0}, 11, 2);
  v.settings.clip = *ClipPlane::fromCoefficients(0, -1, 0, 0);  // cut away the front half (y < 0)
  const RgbaImage img = renderScene(*gl, scene, scene.weighted, 1, v.settings);
  const auto far = v.settings.camera.project({-7, 0, 0}, kSize, kSize);
  REQUIRE(far);
  const double near = luminance(img, v.cx, v.cy, 1.2 * v.rPx, 1.8 * v.rPx);
  const double distant = luminance(img, (*far)[0], (*far)[1], 0, v.rPx);
  INFO("near " << near << ", far " << distant);
  CHECK(near > 1.5 * distant);
  // With the light switched off (beta = 0) the difference goes away: the brightness comes from Eq. 6.
  v.settings.preset.lightingBeta = 0;
  const RgbaImage dark = renderScene(*gl, scene, scene.weighted, 1, v.settings);
  CHECK(luminance(dark, v.cx, v.cy, 1.2 * v.rPx, 1.8 * v.rPx) < 0.5 * near);
}

TEST_CASE("Picking hits the structure at its projected centroid from every named view and none in air") {
  const auto& scene = test::chambersScene();
  const Dataset& ds = scene.dataset;
  for (std::uint16_t label : {std::uint16_t(1), std::uint16_t(2)}) {
    auto frame = structureFrame(ds.labels, label);
    REQUIRE(frame);
    for (NamedView nv : {NamedView::Anterior, NamedView::Posterior, NamedView::LateralLeft, NamedView::LateralRight,
                         NamedView::Superior, NamedView::Inferior}) {
      CAPTURE(toString(nv));
      CAPTURE(label);
      Preset p = contextPreset(RenderMode::Bare, 0);
      View v = viewOf(p, nv, frame->centroidMm, 20, frame->radiusMm);
      SceneVolumes sv{&ds.volume, &ds.labels, &scene.weighted, label};
      const TransferFunction2D table = shadingTable(p);
      const PickResult hit = pick(sv, v.settings, table, v.cx, v.cy);
      REQUIRE(hit.hit);
      CHECK(hit.label == label);
      CHECK(norm(hit.pointMm - frame->centroidMm) < frame->radiusMm + 0.5);
      CHECK(dot(hit.pointMm - frame->centroidMm, v.settings.camera.forward()) < 0);  // the near side
      const PickResult air = pick(sv, v.settings, table, 1, 1);  // a corner: the ray misses the volume
      CHECK_FALSE(air.hit);
      CHECK(air.label == 0);
    }
  }
}

TEST_CASE("CPU picking agrees with the GL image about where opacity crosses one half") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  const auto& scene = test::chambersScene();
  View v = viewOf(contextPreset(RenderMode::Wdt, 0.3f), NamedView::LateralLeft, {0, 0, 0}, 20, 2);
  const RgbaImage img = renderScene(*gl, scene, scene.weighted, 1, v.settings);
  SceneVolumes sv{&scene.dataset.volume, &scene.dataset.labels, &scene.weighted, 1};
  const TransferFunction2D table = shadingTable(v.settings.preset);
  int disagree = 0, total = 0, hits = 0;
  for (int y = 0; y < kSize; y += 3)
    for (int x = 0; x < kSize; x += 3) {
      const PickResult r = pick(sv, v.settings, table, x, y);
      const int a = img.pixel(x, y)[3];
      if (std::abs(a - 128) < 12) continue;  // too close to the threshold to call
      ++total;
      hits += r.hit;
      disagree += r.hit != (a >= 128);
    }
  INFO(disagree << " of " << total << " pixels disagree; " << hits << " hits");
  CHECK(hits > total / 10);
  CHECK(hits < total);
  CHECK(disagree <= total / 50);
}
