// What the paper's figures show, checked on rendered images with their alpha, on the
// full phantom with the shipped presets and on the real abdominal CT with the derived ones:
//   - the selected structure's projected pixels are covered by the highlight hue at opacity ≥ 0.8;
//   - bone surfaces near the structure are shaded: their luminance follows the surface normal;
//   - rays through soft tissue or fluid that meet no bone stay clear (≤ 5 % opacity): no veil;
//   - WDT and the non-weighted field differ where the paper says (Fig. 4): context reached through
//     fluid (the internal auditory canal) shows with WDT and hardly with the non-weighted field;
//     behind dense bone (towards the carotid canal) the two are alike.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "render/derived_preset.h"
#include "render/overlay.h"
#include "render/preset.h"
#include "render/scene.h"
#include "render_fixture.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/mask.h"
#include "wdt/wdt.h"

using namespace at;
using namespace at::render;

namespace {

constexpr int kWidth = 192, kHeight = 144;

const PresetLibrary& shippedPresets() {
  static const PresetLibrary library(test::sourceDir() / "data" / "presets");
  return library;
}

Preset shipped(const std::string& id) {
  auto p = shippedPresets().load(id);
  REQUIRE_MESSAGE(p, test::errorText(p));
  return *p;
}

FloatVolume fieldFor(const Dataset& ds, std::uint16_t label, const Preset& preset) {
  auto params = wdtParamsFor(preset, 2);
  REQUIRE(params);
  params->backend = WdtBackend::Cpu;
  auto wdt = computeWdt(ds.volume, structureMask(ds.labels, label), *params);
  REQUIRE_MESSAGE(wdt, test::errorText(wdt));
  return std::move(wdt->field.distances);
}

// Renders over a transparent background, so alpha is what the volume accumulated.
RgbaImage renderWith(const Dataset& ds, std::uint16_t label, const FloatVolume* field, RenderSettings s) {
  auto* gl = test::glRenderer();
  REQUIRE(gl);
  REQUIRE(gl->setVolume(ds.volume, ds.labels));
  if (field) REQUIRE(gl->setField(*field));
  else gl->clearField();
  gl->setSelected(label);
  s.background = {0, 0, 0, 0};
  s.jitter = false;
  auto img = gl->render(s);
  REQUIRE_MESSAGE(img, test::errorText(img));
  return *img;
}

RenderSettings framed(const Preset& preset, const StructureFrame& frame, const std::string& view, double margin) {
  ViewRequest request;
  request.width = kWidth;
  request.height = kHeight;
  request.view = view;
  request.margin = margin;
  auto s = settingsFor(preset, frame, request);
  REQUIRE(s);
  return *s;
}

double hueDeg(double r, double g, double b) {
  const double mx = std::max({r, g, b}), mn = std::min({r, g, b});
  if (mx - mn < 1e-9) return 0;
  double h = 0;
  if (mx == r) h = std::fmod((g - b) / (mx - mn), 6.0);
  else if (mx == g) h = (b - r) / (mx - mn) + 2;
  else h = (r - g) / (mx - mn) + 4;
  h *= 60;
  return h < 0 ? h + 360 : h;
}

double luminance(const std::array<std::uint8_t, 4>& p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

}  // namespace

TEST_CASE("WDT_PhantomStructures_AreCoveredByTheHighlightHueAtHighOpacity") {
  if (!test::glRenderer()) return;
  const Dataset& ds = test::phantomOfSize(256);
  for (const std::string id : {"cochlea", "lateral_semicircular_canal", "facial_nerve", "stapes"}) {
    CAPTURE(id);
    const Structure* s = ds.findStructure(id);
    REQUIRE(s);
    auto frame = structureFrame(ds.labels, s->label);
    REQUIRE(frame);
    const Preset wdt = shipped(id + "_wdt");
    const FloatVolume field = fieldFor(ds, s->label, wdt);
    const RenderSettings settings = framed(wdt, *frame, wdt.view.value_or("lateral_right"), 1.6);
    const RgbaImage image = renderWith(ds, s->label, &field, settings);
    // The structure's projected pixels: where its bare rendering (opaque surfaces) is drawn, less a
    // pixel of silhouette.
    RenderSettings bareSettings = settings;
    bareSettings.preset.mode = RenderMode::Bare;
    const RgbaImage bare = renderWith(ds, s->label, nullptr, bareSettings);
    const double highlightHue = hueDeg(wdt.highlightRgb[0], wdt.highlightRgb[1], wdt.highlightRgb[2]);
    int inside = 0, covered = 0;
    for (int y = 1; y + 1 < kHeight; ++y)
      for (int x = 1; x + 1 < kWidth; ++x) {
        bool interior = true;
        for (int dy = -1; dy <= 1 && interior; ++dy)
          for (int dx = -1; dx <= 1 && interior; ++dx) interior = bare.pixel(x + dx, y + dy)[3] >= 250;
        if (!interior) continue;
        ++inside;
        const auto p = image.pixel(x, y);
        const double hueOff = std::fabs(hueDeg(p[0], p[1], p[2]) - highlightHue);
        const double mx = std::max({p[0], p[1], p[2]}), mn = std::min({p[0], p[1], p[2]});
        const bool orange = std::min(hueOff, 360 - hueOff) <= 20 && mx > 0 && (mx - mn) / mx >= 0.3;
        covered += p[3] >= 0.8 * 255 && orange;
      }
    INFO(inside << " structure pixels, " << covered << " in the highlight hue at opacity >= 0.8");
    REQUIRE(inside > 100);
    CHECK(covered >= 0.95 * inside);
  }
}

TEST_CASE("WDT_BoneSurfaceNearTheStructure_IsShadedByItsNormal") {
  // A bone ball (1800 HU) beside a small fluid structure, in soft tissue: the ball is context in
  // the first band; seen from the front, its rim (normals across the view) is darker than its
  // centre (normals towards the light), and without shading it is not.
  if (!test::glRenderer()) return;
  Geometry g;
  g.dims = {64, 64, 64};
  g.spacingMm = {0.25, 0.25, 0.25};
  g.originMm = {-7.875, -7.875, -7.875};
  Dataset ds;
  ds.volume = Volume(g, 40);
  ds.labels = LabelMap(g, 0);
  const Vec3 ball{0, 0, 0}, structure{0, -5.0, 0};
  for (int k = 0; k < 64; ++k)
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i) {
        const Vec3 p = g.indexToPatient({double(i), double(j), double(k)});
        if (norm(p - ball) <= 3.0) ds.volume.at(i, j, k) = 1800;
        if (norm(p - structure) <= 1.0) {
          ds.volume.at(i, j, k) = 10;
          ds.labels.at(i, j, k) = 1;
        }
      }
  Preset wdt = shipped("default_wdt");
  wdt.t = 1;  // the whole ball in the context
  const FloatVolume field = fieldFor(ds, 1, wdt);
  RenderSettings s;
  s.preset = wdt;
  s.width = s.height = 96;
  s.camera = Camera::named(NamedView::Anterior, ball, 4.5);  // looking along +y, the structure in front
  s.camera.orbit(0, 30);                                      // from above, past the structure
  const RgbaImage shaded = renderWith(ds, 1, &field, s);
  s.shading = false;
  const RgbaImage flat = renderWith(ds, 1, &field, s);
  const auto c = s.camera.project(ball, 96, 96);
  REQUIRE(c);
  const double rPx = 3.0 / millimetresPerPixel(s.camera, 96);
  const auto ring = [&](const RgbaImage& img, double r0, double r1) {
    double sum = 0;
    int n = 0;
    for (int y = 0; y < 96; ++y)
      for (int x = 0; x < 96; ++x) {
        const double r = std::hypot(x + 0.5 - (*c)[0], y + 0.5 - (*c)[1]) / rPx;
        if (r < r0 || r >= r1 || img.pixel(x, y)[3] < 25) continue;
        sum += luminance(img.pixel(x, y));  // straight colour: the surface's own
        ++n;
      }
    REQUIRE(n > 10);
    return sum / n;
  };
  const double centre = ring(shaded, 0, 0.35), rim = ring(shaded, 0.75, 0.95);
  const double flatCentre = ring(flat, 0, 0.35), flatRim = ring(flat, 0.75, 0.95);
  INFO("shaded: centre " << centre << ", rim " << rim << "; unshaded: centre " << flatCentre << ", rim " << flatRim);
  CHECK(centre > 1.3 * rim);
  CHECK(std::fabs(flatCentre - flatRim) < 0.15 * flatCentre);
}

TEST_CASE("WDT_RaysThroughSoftTissueOrFluidThatMeetNoBone_StayClear") {
  if (!test::glRenderer()) return;
  const auto check = [](const Dataset& ds, std::uint16_t label, const Preset& preset, const RenderSettings& s,
                        double boneHu) {
    const FloatVolume field = fieldFor(ds, label, preset);
    const RgbaImage image = renderWith(ds, label, &field, s);
    const Geometry& g = ds.volume.geometry;
    int clearRays = 0, veiled = 0;
    double worst = 0;
    const double step = 0.5 * std::min({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]});
    for (int y = 0; y < s.height; y += 3)
      for (int x = 0; x < s.width; x += 3) {
        // Along the ray through the volume: the densest HU within a voxel of it, how far it runs
        // through tissue or fluid, and whether it comes within a voxel of the structure.
        const Ray ray = s.camera.rayThroughPixel(x + 0.5, y + 0.5, s.width, s.height);
        double maxHu = -2000, tissueMm = 0;
        bool nearStructure = false;
        for (double t = s.camera.nearMm(); t < s.camera.farMm(); t += step) {
          const Vec3 ijk = g.patientToIndex(ray.origin + t * ray.direction);
          const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
          if (!g.dims.contains(i, j, k)) continue;
          if (ds.volume.at(i, j, k) > -300) tissueMm += step;
          // The voxels a trilinear sample and the smoothed gradient around it read.
          for (int dk = -1; dk <= 1; ++dk)
            for (int dj = -1; dj <= 1; ++dj)
              for (int di = -1; di <= 1; ++di) {
                if (!g.dims.contains(i + di, j + dj, k + dk)) continue;
                maxHu = std::max(maxHu, double(ds.volume.at(i + di, j + dj, k + dk)));
                nearStructure = nearStructure || ds.labels.at(i + di, j + dj, k + dk) == label;
              }
        }
        if (maxHu >= boneHu || tissueMm < 5 || nearStructure) continue;
        ++clearRays;
        const double alpha = image.pixel(x, y)[3] / 255.0;
        worst = std::max(worst, alpha);
        veiled += alpha > 0.05;
      }
    INFO(clearRays << " rays through tissue or fluid only; " << veiled << " above 5 % opacity, worst " << worst);
    REQUIRE(clearRays > 20);
    CHECK(veiled == 0);
  };
  SUBCASE("the phantom: rays through the brain and soft tissue around the bone") {
    const Dataset& ds = test::phantomOfSize(256);
    const Structure* s = ds.findStructure("sigmoid_sinus");
    REQUIRE(s);
    auto frame = structureFrame(ds.labels, s->label);
    REQUIRE(frame);
    const Preset wdt = shipped("sigmoid_sinus_wdt");
    check(ds, s->label, wdt, framed(wdt, *frame, "posterior", 4.0), 300);
  }
#if defined(AT_TEST_HAVE_DATASET_FILES)
  SUBCASE("the abdominal CT with its derived preset: the body is no fog cylinder") {
    if (!test::requireSharedData("totalsegmentator/ct_small.nii.gz")) return;
    const auto dir = test::sharedDataDir() / "totalsegmentator";
    DatasetFiles files;
    files.volumePath = (dir / "ct_small.nii.gz").string();
    files.labelsPath = (dir / "seg_small.nii.gz").string();
    files.namesPath = (dir / "labels.json").string();
    auto ds = openDatasetFiles(files);
    REQUIRE_MESSAGE(ds, test::errorText(ds));
    const Structure* s = ds->findStructure("vertebrae_l1");
    REQUIRE(s);
    auto frame = structureFrame(ds->labels, s->label);
    REQUIRE(frame);
    const Preset wdt = derivedPreset(summariseIntensities(ds->volume), RenderMode::Wdt, s->id);
    check(*ds, s->label, wdt, framed(wdt, *frame, "anterior", 3.0), 150);
  }
#endif
}

TEST_CASE("WDT_AndNonWeightedCochlea_DifferWhereThePaperSays") {
  // Fig. 4: from the cochlea, the WDT reaches the internal auditory canal through the fluid of the
  // labyrinth and the CSF, so the canal's walls show; the non-weighted field, a cloud around the
  // cochlea, hardly reaches them. Through dense bone alone (towards the carotid canal) the two are
  // alike.
  if (!test::glRenderer()) return;
  const Dataset& ds = test::phantomOfSize(256);
  const Structure* cochlea = ds.findStructure("cochlea");
  REQUIRE(cochlea);
  auto frame = structureFrame(ds.labels, cochlea->label);
  REQUIRE(frame);
  const Preset wdt = shipped("cochlea_wdt"), unweighted = shipped("cochlea_unweighted");
  const FloatVolume wdtField = fieldFor(ds, cochlea->label, wdt);
  const FloatVolume unweightedField = fieldFor(ds, cochlea->label, unweighted);
  RenderSettings s = framed(wdt, *frame, "superior", 3.2);
  const RgbaImage wdtImage = renderWith(ds, cochlea->label, &wdtField, s);
  s.preset = unweighted;
  const RgbaImage unweightedImage = renderWith(ds, cochlea->label, &unweightedField, s);
  // Mean alpha over the projection of a structure's voxels (the walls around them are what shows).
  const auto meanAlphaOver = [&](const RgbaImage& img, const char* id) {
    const Structure* t = ds.findStructure(id);
    REQUIRE(t);
    auto f = structureFrame(ds.labels, t->label);
    REQUIRE(f);
    double sum = 0;
    int n = 0;
    for (const Vec3& p : f->pointsMm) {
      const auto px = s.camera.project(p, kWidth, kHeight);
      if (!px || (*px)[0] < 0 || (*px)[1] < 0 || (*px)[0] >= kWidth || (*px)[1] >= kHeight) continue;
      sum += img.pixel(int((*px)[0]), int((*px)[1]))[3];
      ++n;
    }
    REQUIRE(n > 20);
    return sum / n / 255.0;
  };
  const double iacWdt = meanAlphaOver(wdtImage, "internal_auditory_canal");
  const double iacUnweighted = meanAlphaOver(unweightedImage, "internal_auditory_canal");
  const double carotidWdt = meanAlphaOver(wdtImage, "carotid_canal");
  const double carotidUnweighted = meanAlphaOver(unweightedImage, "carotid_canal");
  INFO("internal auditory canal: WDT " << iacWdt << ", non-weighted " << iacUnweighted << "; carotid canal: WDT "
                                       << carotidWdt << ", non-weighted " << carotidUnweighted);
  // Through fluid: the WDT shows the canal, the non-weighted field hardly.
  CHECK(iacWdt > 0.1);
  CHECK(iacWdt > 2.5 * iacUnweighted);
  // Through dense bone the two fields are alike (bone costs about what the non-weighted step does):
  // the WDT gains far less there than along the fluid.
  CHECK(carotidWdt / std::max(carotidUnweighted, 1e-3) < 0.6 * iacWdt / std::max(iacUnweighted, 1e-3));
}

TEST_CASE("WDT_BlendSlider_ChangesTheImageAcrossItsRange") {
  // Algorithm 1's slider t: far context is drawn at t times the data TF's opacity. Each step of
  // the student's slider (0 → 0.15 → 0.3 → 0.6 → 1) must change what is seen, the first step
  // included: the mean change of the image (premultiplied RGB over black, 0..255) between
  // neighbouring steps is at least 4 levels, the first step's (0 → 0.15) at least 10, and more
  // context is drawn as t grows. (Presets whose near context filled the whole view left the first
  // step at about 6 on the cochlea.)
  if (!test::glRenderer()) return;
  const Dataset& ds = test::phantomOfSize(256);
  for (const std::string id : {"posterior_semicircular_canal", "cochlea"}) {
    CAPTURE(id);
    const Structure* s = ds.findStructure(id);
    REQUIRE(s);
    auto frame = structureFrame(ds.labels, s->label);
    REQUIRE(frame);
    Preset wdt = shipped(id + "_wdt");
    const FloatVolume field = fieldFor(ds, s->label, wdt);
    const auto renderAt = [&](float t) {
      wdt.t = t;
      return toRgb(renderWith(ds, s->label, &field, framed(wdt, *frame, wdt.view.value_or("lateral_right"), 1.6)));
    };
    const auto meanOf = [](const RgbImage& img) {
      double sum = 0;
      for (std::uint8_t v : img.rgb) sum += v;
      return sum / double(img.rgb.size());
    };
    const auto meanChange = [](const RgbImage& a, const RgbImage& b) {
      double sum = 0;
      for (std::size_t i = 0; i < a.rgb.size(); ++i) sum += std::abs(int(a.rgb[i]) - int(b.rgb[i]));
      return sum / double(a.rgb.size());
    };
    RgbImage previous = renderAt(0);
    float previousT = 0;
    for (const float t : {0.15f, 0.3f, 0.6f, 1.0f}) {
      const RgbImage image = renderAt(t);
      const double change = meanChange(previous, image);
      INFO("t " << previousT << " -> " << t << ": mean change " << change << ", mean level " << meanOf(previous)
                << " -> " << meanOf(image));
      CHECK(change >= (previousT == 0 ? 10.0 : 4.0));
      CHECK(meanOf(image) > meanOf(previous));
      previous = image;
      previousT = t;
    }
  }
}

TEST_CASE("WDT_ContextBoneNearTheStructure_IsAWhiteSurfaceOfMediumOpacity") {
  // The paper's context: bone near the structure as shaded white surfaces of medium opacity, not a
  // grey veil. A bone plate (1800 HU) 1.5 mm behind a fluid structure, seen through nothing but
  // soft tissue: its pixels away from the structure are drawn at opacity 0.35..0.9 (something
  // behind would still show; the plate is no faint haze) in near-white, unsaturated colour.
  if (!test::glRenderer()) return;
  Geometry g;
  g.dims = {64, 64, 64};
  g.spacingMm = {0.25, 0.25, 0.25};
  g.originMm = {-7.875, -7.875, -7.875};
  Dataset ds;
  ds.volume = Volume(g, 40);
  ds.labels = LabelMap(g, 0);
  for (int k = 0; k < 64; ++k)
    for (int j = 0; j < 64; ++j)
      for (int i = 0; i < 64; ++i) {
        const Vec3 p = g.indexToPatient({double(i), double(j), double(k)});
        if (p[1] >= 1.5 && p[1] <= 3.0 && std::fabs(p[0]) <= 6 && std::fabs(p[2]) <= 6) ds.volume.at(i, j, k) = 1800;
        if (norm(p) <= 1.0) {
          ds.volume.at(i, j, k) = 10;
          ds.labels.at(i, j, k) = 1;
        }
      }
  const Preset wdt = shipped("default_wdt");
  const FloatVolume field = fieldFor(ds, 1, wdt);
  RenderSettings s;
  s.preset = wdt;
  s.width = s.height = 96;
  s.camera = Camera::named(NamedView::Anterior, {0, 0, 0}, 4.0);  // looking along +y at the plate
  const RgbaImage image = renderWith(ds, 1, &field, s);
  double alphaSum = 0, lumSum = 0, satSum = 0;
  int n = 0;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 96; ++x) {
      const double r = std::hypot(x + 0.5 - 48, y + 0.5 - 48);
      if (r < 22 || r > 34) continue;  // off the structure (radius about 12 px), on the plate
      const auto p = image.pixel(x, y);
      const double mx = std::max({p[0], p[1], p[2]}), mn = std::min({p[0], p[1], p[2]});
      alphaSum += p[3] / 255.0;
      lumSum += luminance(p);
      satSum += mx > 0 ? (mx - mn) / mx : 0;
      ++n;
    }
  REQUIRE(n > 100);
  const double alpha = alphaSum / n, lum = lumSum / n, sat = satSum / n;
  INFO("plate: mean opacity " << alpha << ", mean luminance " << lum << " (straight colour), saturation " << sat);
  CHECK(alpha >= 0.35);
  CHECK(alpha <= 0.9);
  CHECK(lum >= 170);
  CHECK(sat <= 0.25);
}
