// Presets derived from plain intensities (render/derived_preset.h) read a CT stored without its
// rescale (HU + 1024: 0 outside the scanner's field of view, about 100 for the air inside it) as
// its HU reading does: the context drawn is the bone, not the skin and soft tissue. The soft
// tissue's level comes from volume/intensity_landmarks.h, shared with the growth defaults.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "render/derived_preset.h"
#include "render/transfer_function.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/intensity_landmarks.h"

using namespace at;
using namespace at::render;

namespace {

// The voxels the derived WDT preset's data TF draws (opacity above 1 %), for `volume` read with
// `levels`.
std::vector<bool> drawnAsContext(const Volume& volume, const IntensityLevels& levels) {
  const Preset wdt = derivedPreset(levels, RenderMode::Wdt, "any");
  auto tf = TransferFunction1D::fromPoints(wdt.dataTf);
  REQUIRE(tf);
  std::vector<float> opacity(65536, 0);
  for (int v = -32768; v <= 32767; ++v) opacity[std::size_t(v + 32768)] = tf->evaluate(v)[3];
  std::vector<bool> out(volume.voxels.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = opacity[std::size_t(volume.voxels[i] + 32768)] > 0.01f;
  return out;
}

double jaccard(const std::vector<bool>& a, const std::vector<bool>& b) {
  std::size_t both = 0, either = 0;
  for (std::size_t i = 0; i < a.size(); ++i) both += a[i] && b[i], either += a[i] || b[i];
  return either ? double(both) / double(either) : 1.0;
}

// The HU volume as a scanner may store it without its rescale: HU + 1024, 0 outside a field-of-view
// cylinder along k, and the air inside it at about 120 (a scanner's own air level, noisy: headsq's
// is 75 … 150).
Volume storedWithoutRescale(const Volume& hu, std::uint64_t seed) {
  Volume out = hu;
  const Dims d = hu.dims();
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0, 25);
  const double cx = 0.5 * (d.x - 1), cy = 0.5 * (d.y - 1), radius = 0.49 * std::min(d.x, d.y);
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) {
        std::int16_t& v = out.voxels[d.index(i, j, k)];
        const bool inField = std::hypot(i - cx, j - cy) <= radius;
        const double stored = !inField ? 0.0 : v <= -900 ? 120.0 + noise(random) : v + 1024.0;
        v = std::int16_t(std::clamp(std::lround(stored), 0L, 4095L));
      }
  return out;
}

// `hu` in the middle of a field of view `pad` voxels wider on each side in i and j, air (−1000 HU)
// around it: a head in a scanner's larger field of view.
Volume inWiderField(const Volume& hu, int pad) {
  const Dims d = hu.dims();
  Geometry g = hu.geometry;
  g.dims = {d.x + 2 * pad, d.y + 2 * pad, d.z};
  Volume out(g, std::int16_t(-1000));
  for (int k = 0; k < d.z; ++k)
    for (int j = 0; j < d.y; ++j)
      for (int i = 0; i < d.x; ++i) out.voxels[g.dims.index(i + pad, j + pad, k)] = hu.voxels[d.index(i, j, k)];
  return out;
}

}  // namespace

TEST_CASE("softTissueLandmarks: the soft tissue's level above a second air level, shifted and scaled with the data") {
  // A histogram shaped as a head CT stored without its rescale: many voxels at 0 (outside the field
  // of view), a broad air peak at `airInside`, a flat tail, soft tissue at `soft`, a little bone.
  for (const int airInside : {60, 100, 140})
    for (const double scale : {0.25, 1.0, 3.0})
      for (const int shift : {-3000, 0, 500}) {
        CAPTURE(airInside);
        CAPTURE(scale);
        CAPTURE(shift);
        std::vector<std::int16_t> voxels;
        std::mt19937_64 random(std::uint64_t(airInside * 31 + shift) ^ std::uint64_t(scale * 1000));
        const auto add = [&](double value, double sigma, int n) {
          std::normal_distribution<double> g(value, sigma);
          for (int i = 0; i < n; ++i) voxels.push_back(std::int16_t(std::lround(shift + scale * std::max(0.0, g(random)))));
        };
        const int soft = 1075;
        add(0, 0, 60000);
        add(airInside, 20, 150000);  // more voxels than the soft tissue's peak
        std::uniform_real_distribution<double> tail(airInside + 60, soft - 100);
        for (int i = 0; i < 20000; ++i) voxels.push_back(std::int16_t(std::lround(shift + scale * tail(random))));
        add(soft, 15, 90000);
        add(2000, 300, 15000);
        const SoftTissueLandmarks l = softTissueLandmarks(valueHistogram(voxels), shift);
        CHECK(l.softTissue >= shift + scale * (soft - 25));
        CHECK(l.softTissue <= shift + scale * (soft + 25));
        CHECK(l.valley > shift + scale * airInside);
        CHECK(l.valley < shift + scale * (soft - 25));
      }
}

TEST_CASE("Derived presets on a CT stored without its rescale draw the voxels its HU reading draws: bone, not skin") {
  // The phantom in a field of view twice as wide: the air inside it outnumbers the soft tissue.
  const Volume head = inWiderField(test::phantomOfSize(96).volume, 48);
  const std::vector<bool> hu = drawnAsContext(head, summariseIntensities(head, IntensityScale::Hounsfield));
  const Volume stored = storedWithoutRescale(head, 1);
  const IntensityLevels plain = summariseIntensities(stored, IntensityScale::Plain);
  const double agreement = jaccard(drawnAsContext(stored, plain), hu);
  MESSAGE("soft tissue read at " << plain.tissue << ", bone drawn from " << plain.denseLow
                                 << "; the voxels drawn agree with the HU reading's by " << agreement);
  // The soft tissue's level is the phantom's soft tissue (about 40 HU: 1064 stored), not the air.
  CHECK(plain.tissue > 1024 - 200);
  CHECK(plain.tissue < 1024 + 200);
  CHECK(agreement >= 0.8);
}

TEST_CASE("Real head CT stored without its rescale (headsq): the derived context is its bone, as with --intercept -1024") {
  if (!test::requireSharedData("headsq/dicom")) return;
  DatasetFiles files;
  files.volumePath = (test::sharedDataDir() / "headsq" / "dicom").string();
  auto ds = openDatasetFiles(files);
  REQUIRE_MESSAGE(ds, test::errorText(ds));
  REQUIRE_FALSE(ds->intensity.hounsfield());  // no value at air's −1000: read as plain intensities
  // `info`, `import` and the desktop say how to read it in HU.
  CHECK(ds->intensity.reason.find("--intercept -1024 reads it in HU") != std::string::npos);
  {
    Volume rescaled = ds->volume;
    IntensityModel model = ds->intensity;
    REQUIRE(applyRescale(rescaled, model, -1024, 1, IntensityChoice::Auto));
    CHECK(model.hounsfield());
    CHECK(model.reason.find("reads it in HU") == std::string::npos);
  }
  const IntensityLevels plain = summariseIntensities(ds->volume, IntensityScale::Plain);
  Volume hu = ds->volume;
  for (auto& v : hu.voxels) v = std::int16_t(v - 1024);
  const std::vector<bool> drawn = drawnAsContext(ds->volume, plain),
                          drawnHu = drawnAsContext(hu, summariseIntensities(hu, IntensityScale::Hounsfield));
  // The soft tissue (−200 … 200 HU on the HU reading): how much of it is drawn as context.
  std::size_t soft = 0, softDrawn = 0, drawnCount = 0;
  for (std::size_t i = 0; i < drawn.size(); ++i) {
    drawnCount += drawn[i];
    if (hu.voxels[i] < -200 || hu.voxels[i] > 200) continue;
    ++soft;
    softDrawn += drawn[i];
  }
  const double agreement = jaccard(drawn, drawnHu), softShare = double(softDrawn) / double(std::max<std::size_t>(1, soft));
  MESSAGE("headsq: soft tissue read at " << plain.tissue << ", bone drawn from " << plain.denseLow << "; " << drawnCount
                                         << " voxels drawn, " << 100 * softShare
                                         << " % of the soft tissue; agreement with the HU reading " << agreement);
  CHECK(plain.tissue > 1000);
  CHECK(plain.tissue < 1150);
  CHECK(softShare < 0.02);
  CHECK(agreement >= 0.8);
}
