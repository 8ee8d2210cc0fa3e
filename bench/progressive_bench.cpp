// progressive_bench: how fast the ray caster's progressive refinement reaches full quality at rest
// (within 2 s at 1280×720 on a 2-core CPU with Mesa llvmpipe, no call over 100 ms; on a
// GPU within one frame), as JSON lines.
//
//   progressive_bench [--volume N] [--structure ID] [--mode MODE] [--size WxH] [--budget MS]
//                     [--views N] [--presets DIR] [--out IMAGE.png]
//
// Set-up: the phantom at N³ (default 256), the structure's shipped preset of MODE (default wdt),
// its WDT computed on the CPU, framed as the `render` command frames it. Then, for each of N
// views (orbiting 25° between them, as a user turning the model and letting go):
//   refine(budget) is called until the image is complete; reported: the number of calls, the
//   longest call, the first call (what the user sees at once), and the wall time to complete.
// Finally one whole-frame render() of the last view for comparison (full_render_ms) and, with
// --out, the converged image. EGL only: no SDL, DCMTK or SQLite.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <vector>

#include "render/gl/egl_context.h"
#include "render/gl/volume_renderer.h"
#include "render/gradient_volume.h"
#include "render/image.h"
#include "render/preset.h"
#include "render/scene.h"
#include "volume/mask.h"
#include "volume/phantom.h"
#include "volume/png_image.h"
#include "wdt/wdt.h"

using namespace at;
using Clock = std::chrono::steady_clock;

namespace {

double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

// CPU time of the whole process (every thread: llvmpipe's rasteriser threads included), in ms.
double processCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) * 1e3 + double(ts.tv_nsec) * 1e-6;
}

struct Options {
  int volume = 256, width = 1280, height = 720, views = 3;
  double budgetMs = 70;
  std::string structure = "cochlea", mode = "wdt", out;
  std::string presets = AT_BENCH_PRESETS_DIR;
};

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--size" && (v = next())) {
      if (std::sscanf(v, "%dx%d", &o.width, &o.height) != 2) return false;
    } else if (a == "--volume" && (v = next())) o.volume = std::atoi(v);
    else if (a == "--views" && (v = next())) o.views = std::atoi(v);
    else if (a == "--budget" && (v = next())) o.budgetMs = std::atof(v);
    else if (a == "--structure" && (v = next())) o.structure = v;
    else if (a == "--mode" && (v = next())) o.mode = v;
    else if (a == "--presets" && (v = next())) o.presets = v;
    else if (a == "--out" && (v = next())) o.out = v;
    else return false;
  }
  return o.width > 0 && o.height > 0 && o.volume >= 16 && o.views > 0 && o.budgetMs > 0;
}

int failWith(const std::string& m) {
  std::fprintf(stderr, "progressive_bench: %s\n", m.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) {
    std::fprintf(stderr, "usage: progressive_bench [--volume N] [--structure ID] [--mode MODE] [--size WxH] "
                         "[--budget MS] [--views N] [--presets DIR] [--out IMAGE.png]\n");
    return 2;
  }
  auto mode = render::parseRenderMode(o.mode);
  if (!mode) return failWith(mode.error().message);
  auto ctx = render::gl::EglContext::create();
  if (!ctx) return failWith(ctx.error().message);
  auto renderer = render::gl::VolumeRenderer::create();
  if (!renderer) return failWith(renderer.error().message);

  const Dataset ds = makePhantom({o.volume, 51.2, 1});
  const Structure* s = ds.findStructure(o.structure);
  if (!s) return failWith("phantom has no structure '" + o.structure + "'");
  auto preset = render::PresetLibrary(o.presets).forStructure(s->id, *mode);
  if (!preset) return failWith(preset.error().message);
  const auto tg = Clock::now();
  const render::GradientVolume gradients = render::computeGradientVolume(ds.volume);
  const double gradientMs = msSince(tg);
  if (auto st = renderer->setVolume(ds.volume, ds.labels, gradients); !st) return failWith(st.error().message);
  double wdtMs = 0;
  if (render::modeNeedsField(*mode)) {
    auto params = render::wdtParamsFor(*preset);
    if (!params) return failWith(params.error().message);
    params->backend = WdtBackend::Cpu;
    auto wdt = computeWdt(ds.volume, structureMask(ds.labels, s->label), *params);
    if (!wdt) return failWith(wdt.error().message);
    wdtMs = wdt->stats.msTotal;
    if (auto st = renderer->setField(wdt->field.distances); !st) return failWith(st.error().message);
  }
  renderer->setSelected(s->label);
  auto frame = render::structureFrame(ds.labels, s->label);
  if (!frame) return failWith(frame.error().message);
  render::ViewRequest request;
  request.width = o.width;
  request.height = o.height;
  auto settings = render::settingsFor(*preset, *frame, request);
  if (!settings) return failWith(settings.error().message);
  settings->background = {0.04f, 0.04f, 0.05f, 1.0f};
  if (const char* e = std::getenv("AT_BENCH_STEP_VOXELS")) settings->stepMm = std::atof(e) * ds.volume.geometry.spacingMm[0];
  if (std::getenv("AT_BENCH_NO_SHADING")) settings->shading = false;
  // Compile the program variant and build the tables before timing.
  {
    render::RenderSettings tiny = *settings;
    tiny.width = tiny.height = 8;
    if (auto img = renderer->render(tiny); !img) return failWith(img.error().message);
  }
  std::vector<double> converge;
  double worstCall = 0;
  for (int v = 0; v < o.views; ++v) {
    if (v > 0) settings->camera.orbit(25, 0);
    const auto t0 = Clock::now();
    const double cpuStart = processCpuMs();
    int calls = 0;
    double maxCall = 0, firstCall = 0;
    render::gl::RefineProgress p;
    do {
      auto r = renderer->refine(*settings, o.budgetMs);
      if (!r) return failWith(r.error().message);
      p = *r;
      if (calls == 0) firstCall = p.ms;
      maxCall = std::max(maxCall, p.ms);
      ++calls;
    } while (!p.complete && calls < 100000);
    const double total = msSince(t0), cpu = processCpuMs() - cpuStart;
    converge.push_back(total);
    worstCall = std::max(worstCall, maxCall);
    std::printf("{\"bench\":\"progressive_view\",\"view\":%d,\"calls\":%d,\"first_call_ms\":%.1f,\"max_call_ms\":%.1f,"
                "\"time_to_full_ms\":%.0f,\"cpu_ms\":%.0f}\n",
                v, calls, firstCall, maxCall, total, cpu);
    std::fflush(stdout);
  }
  const auto tf = Clock::now();
  const double cpu0 = processCpuMs();
  auto full = renderer->render(*settings);
  if (!full) return failWith(full.error().message);
  const double fullMs = msSince(tf), fullCpuMs = processCpuMs() - cpu0;
  renderer->setRayCaster(render::gl::RayCaster::Fragment);
  if (auto warm = renderer->render(*settings); !warm) return failWith(warm.error().message);
  const auto tfr = Clock::now();
  auto fragment = renderer->render(*settings);
  if (!fragment) return failWith(fragment.error().message);
  std::printf("{\"bench\":\"full_render\",\"compute_ms\":%.0f,\"compute_cpu_ms\":%.0f,\"fragment_ms\":%.0f}\n", fullMs,
              fullCpuMs, msSince(tfr));
  std::sort(converge.begin(), converge.end());
  std::printf("{\"bench\":\"progressive\",\"device\":\"%s\",\"width\":%d,\"height\":%d,\"volume\":%d,\"structure\":\"%s\","
              "\"mode\":\"%s\",\"budget_ms\":%.0f,\"views\":%d,\"time_to_full_ms_max\":%.0f,\"time_to_full_ms_median\":%.0f,"
              "\"max_call_ms\":%.1f,\"full_render_ms\":%.0f,\"gradient_ms\":%.0f,\"wdt_ms\":%.0f}\n",
              ctx->description().c_str(), o.width, o.height, o.volume, s->id.c_str(), o.mode.c_str(), o.budgetMs, o.views,
              converge.back(), converge[converge.size() / 2], worstCall, fullMs, gradientMs, wdtMs);
  if (std::getenv("AT_BENCH_DEBUG")) {
    double sums[3] = {0, 0, 0};
    for (std::size_t i = 0; i < full->rgba.size(); i += 4)
      for (int c = 0; c < 3; ++c) sums[c] += full->rgba[i + std::size_t(c)] * 1024.0 / 255.0;
    const double n = double(full->rgba.size() / 4);
    std::printf("{\"iterations\":%.1f,\"hu_samples\":%.1f,\"full_samples\":%.1f}\n", sums[0] / n, sums[1] / n, sums[2] / n);
  }
  if (!o.out.empty()) {
    auto shown = renderer->readDisplay();
    if (!shown) return failWith(shown.error().message);
    if (auto st = writePng(o.out, render::toRgb(*shown)); !st) return failWith(st.error().message);
  }
  return 0;
}
