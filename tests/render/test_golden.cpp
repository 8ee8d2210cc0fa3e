// Golden images: small renders of the phantom with the shipped presets, compared with approved
// references in tests/render/golden/ under a tolerance (mean |diff| ≤ 2/255 and at most 1 % of
// pixels off by more than 16 in some channel). A failing render is written next to the test
// output (build/render_golden/NAME.actual.png, NAME.diff.png). Re-approve: scripts/approve_golden.sh.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>

#include "render/preset.h"
#include "render/scene.h"
#include "render_fixture.h"
#include "test_support.h"
#include "volume/dataset_source.h"
#include "volume/mask.h"
#include "volume/png_image.h"
#include "wdt/wdt.h"

using namespace at;
using namespace at::render;
namespace fs = std::filesystem;

namespace {

const Dataset& phantom64() {
  static const Dataset ds = [] {
    auto d = openBuiltinDataset("phantom:64");
    REQUIRE_MESSAGE(d, d.error().message);
    return std::move(*d);
  }();
  return ds;
}

struct Golden {
  const char* name;
  const char* structure;
  RenderMode mode;
  const char* view;
};

struct Comparison {
  double meanAbs = 0;
  double shareOff = 0;
};

Comparison compare(const RgbImage& a, const RgbImage& b, RgbImage& diff) {
  Comparison c;
  diff = RgbImage(a.width, a.height);
  std::size_t off = 0;
  double sum = 0;
  for (int y = 0; y < a.height; ++y)
    for (int x = 0; x < a.width; ++x) {
      int worst = 0;
      for (int ch = 0; ch < 3; ++ch) {
        const int d = std::abs(int(a.pixel(x, y)[ch]) - int(b.pixel(x, y)[ch]));
        sum += d;
        worst = std::max(worst, d);
      }
      off += worst > 16;
      diff.pixel(x, y)[0] = std::uint8_t(std::min(255, worst * 8));
    }
  c.meanAbs = sum / (3.0 * a.width * a.height);
  c.shareOff = double(off) / (double(a.width) * a.height);
  return c;
}

}  // namespace

TEST_CASE("Golden renders of the phantom match their approved references") {
  auto* gl = test::glRenderer();
  if (!gl) return;
  const Dataset& ds = phantom64();
  const PresetLibrary library(test::sourceDir() / "data" / "presets");
  const bool approve = std::getenv("AT_APPROVE_GOLDEN") != nullptr;
  const Golden goldens[] = {
      {"cochlea_wdt", "cochlea", RenderMode::Wdt, "lateral_left"},
      {"cochlea_bare", "cochlea", RenderMode::Bare, "lateral_left"},
      {"lateral_canal_lighting", "lateral_semicircular_canal", RenderMode::Lighting, "superior"},
  };
  REQUIRE(gl->setVolume(ds.volume, ds.labels));
  for (const Golden& g : goldens) {
    CAPTURE(g.name);
    const Structure* s = ds.findStructure(g.structure);
    REQUIRE(s);
    auto preset = library.forStructure(s->id, g.mode);
    REQUIRE_MESSAGE(preset, preset.error().message);
    auto frame = structureFrame(ds.labels, s->label);
    REQUIRE(frame);
    if (modeNeedsField(g.mode)) {
      auto params = wdtParamsFor(*preset, 2);
      REQUIRE(params);
      params->backend = WdtBackend::Cpu;
      auto wdt = computeWdt(ds.volume, structureMask(ds.labels, s->label), *params);
      REQUIRE_MESSAGE(wdt, wdt.error().message);
      REQUIRE(gl->setField(wdt->field.distances));
    }
    gl->setSelected(s->label);
    ViewRequest req;
    req.width = req.height = 128;
    req.view = g.view;
    auto settings = settingsFor(*preset, *frame, req);
    REQUIRE(settings);
    settings->jitter = false;  // references must not depend on the hash's float precision
    auto img = gl->render(*settings);
    REQUIRE_MESSAGE(img, img.error().message);
    const RgbImage rgb = toRgb(*img);
    // Semantic check beside the snapshot: a point of the structure projects onto a drawn pixel.
    auto c = settings->camera.project(frame->anchorMm, 128, 128);
    REQUIRE(c);
    CHECK(img->pixel(int((*c)[0]), int((*c)[1]))[3] > 0);

    const fs::path reference = test::sourceDir() / "tests" / "render" / "golden" / (std::string(g.name) + ".png");
    if (approve) {
      REQUIRE(writePng(reference.string(), rgb));
      MESSAGE("approved " << reference.string());
      continue;
    }
    auto ref = readPng(reference.string());
    if (!ref || ref->width != rgb.width || ref->height != rgb.height) {
      FAIL_CHECK("no usable reference " << reference.string() << " (run scripts/approve_golden.sh)");
      continue;
    }
    RgbImage diff;
    const Comparison cmp = compare(rgb, *ref, diff);
    const bool ok = cmp.meanAbs <= 2.0 && cmp.shareOff <= 0.01;
    if (!ok) {
      const fs::path dir = fs::path(AT_BINARY_DIR) / "render_golden";
      fs::create_directories(dir);
      (void)writePng((dir / (std::string(g.name) + ".actual.png")).string(), rgb);
      (void)writePng((dir / (std::string(g.name) + ".diff.png")).string(), diff);
      MESSAGE("failing render written to " << (dir / (std::string(g.name) + ".actual.png")).string());
    }
    INFO("mean |diff| " << cmp.meanAbs << "/255, " << cmp.shareOff * 100 << " % of pixels off by > 16");
    CHECK(ok);
  }
}
