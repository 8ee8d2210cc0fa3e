// render_bench: GPU frame time of the ray caster and the hover cycle, as JSON lines.
//
//   render_bench [--size WxH] [--volume N] [--hover-volume N] [--frames N] [--warmup N]
//                [--cycles N] [--structure ID] [--presets DIR] [--field-downsample F]
//                [--ray-caster compute|fragment] [--step-voxels S] [--compare-step S [--images DIR]]
//                [--unit field|size] [--mode wdt|fuzzy|lighting|outline|unweighted]
//
// 1. frame: phantom at N³ (default 512), the structure's WDT preset with Phong shading, a field
//    from computeWdt (backend auto; downsampled by F for the 512³ set-up), GPU time of each frame
//    from GL timer queries; median and p90 of `frames` after `warmup`.
// 2. hover: phantom at M³ (default 256): pick under the cursor (CPU) → full-resolution WDT of the
//    picked structure (CUDA when available) → field into the GL texture → next frame (glFinish);
//    wall-clock per step and end to end, for `cycles` hovers alternating between structures.
// --ray-caster picks the shader stage that casts the rays (same image); --step-voxels sets the
// sampling step to S × the smallest spacing (default: the renderer's, half a voxel).
// --compare-step renders the frame set-up once with the default step and once with S voxels and
// prints how far the images differ (mean |diff| per channel, share of pixels off by > 16), writing
// both as PNG into DIR with --images.
// --unit field (default) sets the distance unit as every front end does (render::applyFieldScale on
// the frame's view: the field's bone in view and the view's rays) and reports what that measure
// costs on the CPU (first call and median of 5) as a field_scale line; in the hover cycle the
// desktop measures it again for each new field (DesktopModel::fieldScaleOf), so each cycle also
// copies the field to the host and measures it (field_scale_ms, total_with_scale_ms). --unit size
// keeps the unit from the structure's size alone (render::settingsFor), as before the measure.
// --mode picks the frame's preset mode (default wdt): fuzzy and lighting add the measure of the bone
// seen next to the structure (render::neighbourBone) to the field_scale line's cost.
// EGL only: no SDL, DCMTK or SQLite.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "render/gl/egl_context.h"
#include "render/gl/volume_renderer.h"
#include "render/field_scale.h"
#include "render/image.h"
#include "render/preset.h"
#include "render/scene.h"
#include "volume/mask.h"
#include "volume/phantom.h"
#include "volume/png_image.h"
#include "wdt/problem.h"
#include "wdt/wdt.h"

#if defined(AT_HAVE_CUDA)
#include "cuda/wdt_cuda.h"
#endif

using namespace at;
using Clock = std::chrono::steady_clock;

namespace {

double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const std::size_t i = std::min(v.size() - 1, std::size_t(q * double(v.size() - 1) + 0.5));
  return v[i];
}

struct Options {
  int width = 1920, height = 1080, volume = 512, hoverVolume = 256, frames = 100, warmup = 10, cycles = 10;
  int fieldDownsample = 2;
  double stepVoxels = 0;  // 0: the renderer's default step
  double compareStepVoxels = 0;
  std::string imagesDir;
  render::gl::RayCaster rayCaster = render::gl::RayCaster::Compute;
  std::string structure = "cochlea";
  std::string presets = AT_BENCH_PRESETS_DIR;
  bool fieldUnit = true;  // --unit field|size
  render::RenderMode mode = render::RenderMode::Wdt;  // the frame's preset (--mode)
};

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto next = [&]() -> const char* { return i + 1 < argc ? argv[++i] : nullptr; };
    const char* v = nullptr;
    if (a == "--size" && (v = next())) {
      if (std::sscanf(v, "%dx%d", &o.width, &o.height) != 2) return false;
    } else if (a == "--volume" && (v = next())) o.volume = std::atoi(v);
    else if (a == "--hover-volume" && (v = next())) o.hoverVolume = std::atoi(v);
    else if (a == "--frames" && (v = next())) o.frames = std::atoi(v);
    else if (a == "--warmup" && (v = next())) o.warmup = std::atoi(v);
    else if (a == "--cycles" && (v = next())) o.cycles = std::atoi(v);
    else if (a == "--field-downsample" && (v = next())) o.fieldDownsample = std::atoi(v);
    else if (a == "--step-voxels" && (v = next())) o.stepVoxels = std::atof(v);
    else if (a == "--compare-step" && (v = next())) o.compareStepVoxels = std::atof(v);
    else if (a == "--images" && (v = next())) o.imagesDir = v;
    else if (a == "--ray-caster" && (v = next())) {
      if (std::string(v) == "compute") o.rayCaster = render::gl::RayCaster::Compute;
      else if (std::string(v) == "fragment") o.rayCaster = render::gl::RayCaster::Fragment;
      else return false;
    } else if (a == "--structure" && (v = next())) o.structure = v;
    else if (a == "--presets" && (v = next())) o.presets = v;
    else if (a == "--unit" && (v = next())) {
      if (std::string(v) == "field") o.fieldUnit = true;
      else if (std::string(v) == "size") o.fieldUnit = false;
      else return false;
    } else if (a == "--mode" && (v = next())) {
      auto mode = render::parseRenderMode(v);
      if (!mode) return false;
      o.mode = *mode;
    } else return false;
  }
  return o.width > 0 && o.height > 0 && o.volume > 8 && o.hoverVolume > 8 && o.frames > 0 && o.cycles > 0 &&
         o.fieldDownsample >= 1 && o.stepVoxels >= 0 && o.compareStepVoxels >= 0;
}

int failWith(const std::string& m) {
  std::fprintf(stderr, "render_bench: %s\n", m.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) {
    std::fprintf(stderr,
                 "usage: render_bench [--size WxH] [--volume N] [--hover-volume N] [--frames N] [--warmup N] "
                 "[--cycles N] [--structure ID] [--presets DIR] [--field-downsample F] "
                 "[--ray-caster compute|fragment] [--step-voxels S] [--compare-step S [--images DIR]] "
                 "[--unit field|size] [--mode wdt|fuzzy|lighting|outline|unweighted]\n");
    return 2;
  }
  auto ctx = render::gl::EglContext::create();
  if (!ctx) return failWith(ctx.error().message);
  auto renderer = render::gl::VolumeRenderer::create();
  if (!renderer) return failWith(renderer.error().message);
  renderer->setRayCaster(o.rayCaster);
  const char* rayCasterName = o.rayCaster == render::gl::RayCaster::Compute ? "compute" : "fragment";
  const auto stepFor = [&](const Geometry& g) {
    return o.stepVoxels > 0 ? o.stepVoxels * std::min({g.spacingMm[0], g.spacingMm[1], g.spacingMm[2]}) : 0.0;
  };
  const render::PresetLibrary library(o.presets);

  // 1. Frame time at full size.
  {
    const auto t0 = Clock::now();
    const Dataset ds = makePhantom({o.volume, 51.2, 1});
    const double phantomMs = msSince(t0);
    const Structure* s = ds.findStructure(o.structure);
    if (!s) return failWith("phantom has no structure '" + o.structure + "'");
    auto preset = library.forStructure(s->id, o.mode);
    if (!preset) return failWith(preset.error().message);
    auto params = render::wdtParamsFor(*preset);
    if (!params) return failWith(params.error().message);
    params->downsample = o.fieldDownsample;
    auto wdt = computeWdt(ds.volume, structureMask(ds.labels, s->label), *params);
    if (!wdt) return failWith(wdt.error().message);
    if (auto st = renderer->setVolume(ds.volume, ds.labels); !st) return failWith(st.error().message);
    if (auto st = renderer->setField(wdt->field.distances); !st) return failWith(st.error().message);
    renderer->setSelected(s->label);
    auto frame = render::structureFrame(ds.labels, s->label);
    if (!frame) return failWith(frame.error().message);
    render::ViewRequest req;
    req.width = o.width;
    req.height = o.height;
    auto settings = render::settingsFor(*preset, *frame, req);
    if (!settings) return failWith(settings.error().message);
    settings->shading = true;
    settings->stepMm = stepFor(ds.volume.geometry);
    if (o.fieldUnit) {
      // The unit as the render command and the desktop set it, once per field and framed view.
      std::vector<double> scaleMs;
      render::FieldScale scale;
      for (int i = 0; i < 5; ++i) {
        render::RenderSettings measured = *settings;
        const auto ts = Clock::now();
        scale = render::applyFieldScale(measured, wdt->field.distances, ds.volume, nullptr, *frame, req);
        scaleMs.push_back(msSince(ts));
        if (i == 0) *settings = measured;
      }
      std::printf("{\"bench\":\"field_scale\",\"mode\":\"%s\",\"volume\":%d,\"field_grid\":\"%s\",\"width\":%d,\"height\":%d,"
                  "\"first_ms\":%.1f,\"ms_median\":%.1f,\"view_rays\":%zu,\"derived\":%s,\"from_seen\":%s,"
                  "\"capped_by_rays\":%s,\"distance_unit\":%.4f,\"distance_offset\":%.4f,\"size_unit\":%.4f}\n",
                  render::toString(o.mode), o.volume, wdt->field.distances.dims().toString().c_str(), o.width, o.height, scaleMs[0],
                  percentile(scaleMs, 0.5), scale.viewRays, scale.derived ? "true" : "false",
                  scale.fromSeen ? "true" : "false", scale.cappedByRays ? "true" : "false", settings->distanceUnit,
                  settings->distanceOffset, render::distanceUnitFor(*frame));
      std::fflush(stdout);
    }
    std::vector<double> gpuMs;
    for (int i = 0; i < o.warmup + o.frames; ++i) {
      auto ms = renderer->renderTimed(*settings);
      if (!ms) return failWith(ms.error().message);
      if (i >= o.warmup) gpuMs.push_back(*ms);
    }
    const double median = percentile(gpuMs, 0.5);
    std::printf(
        "{\"bench\":\"render_frame\",\"device\":\"%s\",\"width\":%d,\"height\":%d,\"volume\":%d,\"field_grid\":\"%s\","
        "\"structure\":\"%s\",\"preset\":\"%s\",\"frames\":%d,\"gpu_ms_median\":%.3f,\"gpu_ms_p90\":%.3f,"
        "\"fps_median\":%.1f,\"phantom_ms\":%.0f,\"wdt_ms\":%.1f,\"wdt_device\":\"%s\",\"ray_caster\":\"%s\","
        "\"step_mm\":%.4f,\"unit\":\"%s\",\"distance_unit\":%.4f}\n",
        ctx->description().c_str(), o.width, o.height, o.volume,
        wdt->field.distances.dims().toString().c_str(), s->id.c_str(), preset->id.value_or("?").c_str(), o.frames,
        median, percentile(gpuMs, 0.9), median > 0 ? 1000.0 / median : 0.0, phantomMs, wdt->stats.msTotal,
        wdt->stats.device.c_str(), rayCasterName, render::effectiveStepMm(ds.volume.geometry, *settings),
        o.fieldUnit ? "field" : "size", settings->distanceUnit);
    std::fflush(stdout);
    if (o.compareStepVoxels > 0) {
      render::RenderSettings standard = *settings;
      standard.stepMm = 0;  // the renderer's default step
      auto reference = renderer->render(standard);
      if (!reference) return failWith(reference.error().message);
      render::RenderSettings coarse = *settings;
      coarse.stepMm = o.compareStepVoxels * std::min({ds.volume.geometry.spacingMm[0], ds.volume.geometry.spacingMm[1],
                                                      ds.volume.geometry.spacingMm[2]});
      auto other = renderer->render(coarse);
      if (!other) return failWith(other.error().message);
      const RgbImage a = render::toRgb(*reference), b = render::toRgb(*other);
      double sum = 0;
      std::size_t off = 0;
      for (std::size_t p = 0; p < a.rgb.size(); p += 3) {
        int worst = 0;
        for (std::size_t c = 0; c < 3; ++c) {
          const int d = std::abs(int(a.rgb[p + c]) - int(b.rgb[p + c]));
          sum += d;
          worst = std::max(worst, d);
        }
        off += worst > 16;
      }
      const double pixels = double(a.rgb.size() / 3);
      std::printf("{\"bench\":\"step_compare\",\"volume\":%d,\"width\":%d,\"height\":%d,\"step_mm\":%.4f,"
                  "\"other_step_mm\":%.4f,\"mean_abs_diff\":%.3f,\"share_off_by_16\":%.5f}\n",
                  o.volume, o.width, o.height, render::effectiveStepMm(ds.volume.geometry, standard), coarse.stepMm,
                  sum / (3 * pixels), double(off) / pixels);
      std::fflush(stdout);
      if (!o.imagesDir.empty()) {
        if (auto st = writePng(o.imagesDir + "/step_reference.png", a); !st) return failWith(st.error().message);
        if (auto st = writePng(o.imagesDir + "/step_other.png", b); !st) return failWith(st.error().message);
      }
    }
  }

  // 2. Hover cycle.
  {
    const Dataset ds = makePhantom({o.hoverVolume, 51.2, 1});
    if (auto st = renderer->setVolume(ds.volume, ds.labels); !st) return failWith(st.error().message);
    const Structure* first = ds.findStructure(o.structure);
    if (!first) return failWith("phantom has no structure '" + o.structure + "'");
    auto preset = library.forStructure(first->id, render::RenderMode::Wdt);
    if (!preset) return failWith(preset.error().message);
    auto frame = render::structureFrame(ds.labels, first->label);
    if (!frame) return failWith(frame.error().message);
    render::ViewRequest req;
    req.width = o.width;
    req.height = o.height;
    req.margin = 4;  // a wide view: several structures to hover
    auto settings = render::settingsFor(*preset, *frame, req);
    if (!settings) return failWith(settings.error().message);
    settings->stepMm = stepFor(ds.volume.geometry);
    // Hover targets: the projected centroids of the structures visible in bare mode from this view.
    render::RenderSettings pickSettings = *settings;
    pickSettings.preset.mode = render::RenderMode::Bare;
    const render::TransferFunction2D table = render::shadingTable(pickSettings.preset);
    struct Target {
      std::uint16_t label;
      double x, y;
      render::StructureFrame frame;  // measured once, as the desktop keeps each structure's frame
    };
    std::vector<Target> targets;
    for (const Structure& s : ds.structures) {
      auto f = render::structureFrame(ds.labels, s.label);
      if (!f) continue;
      auto px = settings->camera.project(f->anchorMm, o.width, o.height);
      if (!px || (*px)[0] < 0 || (*px)[1] < 0 || (*px)[0] >= o.width || (*px)[1] >= o.height) continue;
      targets.push_back({s.label, (*px)[0], (*px)[1], *f});
    }
    const render::FieldView hoverView = render::fieldViewOf(*settings);
    const render::BoneLevels hoverBone = render::boneLevels(*preset);
    if (targets.empty()) return failWith("no structure projects into the hover view");
    std::vector<double> totals, frameGpu, totalsWithScale, scaleMsAll;
#if defined(AT_HAVE_CUDA)
    // The volume and labels go to the device once, as the renderer's textures do when a dataset
    // opens; each hover then builds its density bytes and seeds there.
    std::optional<cuda::DeviceVolume> deviceVolume;
    if (cuda::queryDevice().available) {
      const auto tu = Clock::now();
      auto uploaded = cuda::uploadVolume(ds.volume, ds.labels);
      if (!uploaded) return failWith(uploaded.error().message);
      deviceVolume = std::move(*uploaded);
      std::printf("{\"bench\":\"hover_setup\",\"volume\":%d,\"device_volume_upload_ms\":%.2f}\n", o.hoverVolume,
                  msSince(tu));
    }
#endif
    {
      // What the desktop does when a dataset opens (VolumeView::takeDataset/prepare): every
      // ray-caster variant run once, and the field texture registered with CUDA on the volume's
      // grid, so that no hover pays either.
      const auto tw = Clock::now();
      if (auto st = renderer->warmUp(*settings); !st) return failWith(st.error().message);
      const double warmMs = msSince(tw);
      const auto tr = Clock::now();
      auto reserved = renderer->reserveDeviceField(ds.volume.dims());
      if (!reserved) return failWith(reserved.error().message);
      std::printf("{\"bench\":\"hover_open\",\"volume\":%d,\"warm_up_ms\":%.2f,\"field_reserved\":%s,\"reserve_ms\":%.2f}\n",
                  o.hoverVolume, warmMs, *reserved ? "true" : "false", msSince(tr));
    }
    renderer->takeCosts();
    for (int c = 0; c < o.cycles; ++c) {
      const Target& tg = targets[std::size_t(c) % targets.size()];
      const auto t0 = Clock::now();
      render::SceneVolumes scene{&ds.volume, &ds.labels, nullptr, tg.label};
      const render::PickResult hit = render::pick(scene, pickSettings, table, tg.x, tg.y);
      const double pickMs = msSince(t0);
      const std::uint16_t label = hit.hit && hit.label ? hit.label : tg.label;
      auto params = render::wdtParamsFor(*preset);
      if (!params) return failWith(params.error().message);
      const auto t1 = Clock::now();
      double wdtMs = 0, uploadMs = 0, downloadMs = 0, scaleMs = 0;
      FloatVolume hostField;
      std::string wdtDevice;
      int passesRun = 0;
      bool onDevice = false;
#if defined(AT_HAVE_CUDA)
      if (deviceVolume) {
        // The GPU path: nothing is uploaded, and the field stays in device memory and goes into
        // the GL texture directly.
        WdtStats stats;
        auto dfield = cuda::runCudaBackendOnDevice(*deviceVolume, label, *params, {}, &stats);
        if (!dfield) return failWith(dfield.error().message);
        wdtMs = msSince(t1);
        wdtDevice = stats.device;
        passesRun = stats.passesRun;
        const auto t2 = Clock::now();
        if (auto st = renderer->setFieldFromDevice(*dfield); !st) return failWith(st.error().message);
        uploadMs = msSince(t2);
        onDevice = true;
        if (o.fieldUnit) {
          // The host copy the desktop keeps for picking, which its unit is measured on.
          const auto td = Clock::now();
          if (auto st = cuda::copyToHost(*dfield, hostField); !st) return failWith(st.error().message);
          downloadMs = msSince(td);
        }
      }
#endif
      if (!onDevice) {
        auto wdt = computeWdt(ds.volume, structureMask(ds.labels, label), *params);
        if (!wdt) return failWith(wdt.error().message);
        wdtMs = msSince(t1);
        wdtDevice = wdt->stats.device;
        passesRun = wdt->stats.passesRun;
        const auto t2 = Clock::now();
        if (auto st = renderer->setField(wdt->field.distances); !st) return failWith(st.error().message);
        uploadMs = msSince(t2);
        hostField = std::move(wdt->field.distances);
      }
      renderer->setSelected(label);
      render::RenderSettings cycleSettings = *settings;
      if (o.fieldUnit) {
        // DesktopModel::fieldScaleOf: the new field's unit on the framed view, before its first frame.
        const render::StructureFrame* labelFrame = &tg.frame;
        for (const Target& other : targets)
          if (other.label == label) labelFrame = &other.frame;
        const auto ts = Clock::now();
        const render::FieldScale scale = render::fieldScale(hostField, ds.volume, nullptr, *labelFrame, hoverBone, &hoverView);
        scaleMs = msSince(ts);
        cycleSettings.distanceUnit = scale.distanceUnit;
        cycleSettings.distanceOffset = scale.distanceOffset;
      }
      const auto t3 = Clock::now();
      auto gpu = renderer->renderTimed(cycleSettings);  // waits for the GPU result
      if (!gpu) return failWith(gpu.error().message);
      const double frameMs = msSince(t3);
      // total: pick, field, upload and frame, as before the unit was measured per field; the host
      // copy and the measure are reported beside it (total_with_scale_ms: the whole cycle).
      const double totalWithScale = msSince(t0);
      const double total = totalWithScale - downloadMs - scaleMs;
      // The frame's CPU side: the renderer's preparation (mask, table, occupancy, uniforms).
      const render::gl::PrepareCosts costs = renderer->takeCosts();
      totals.push_back(total);
      frameGpu.push_back(*gpu);
      totalsWithScale.push_back(totalWithScale);
      scaleMsAll.push_back(scaleMs);
      std::printf(
          "{\"bench\":\"hover_cycle\",\"volume\":%d,\"cycle\":%d,\"picked_label\":%u,\"pick_hit\":%s,\"pick_ms\":%.3f,"
          "\"wdt_ms\":%.2f,\"wdt_device\":\"%s\",\"wdt_passes\":%d,\"field_path\":\"%s\",\"field_upload_ms\":%.2f,\"frame_ms\":%.2f,"
          "\"frame_gpu_ms\":%.3f,\"prepare_ms\":%.3f,\"mask_ms\":%.3f,\"occupancy_ms\":%.3f,\"table_ms\":%.3f,"
          "\"field_download_ms\":%.2f,\"field_scale_ms\":%.2f,\"total_ms\":%.2f,\"total_with_scale_ms\":%.2f}\n",
          o.hoverVolume, c, unsigned(label), hit.hit ? "true" : "false", pickMs, wdtMs, wdtDevice.c_str(), passesRun,
          onDevice ? "cuda-gl interop" : "host upload", uploadMs, frameMs, *gpu, costs.prepareMs, costs.maskMs,
          costs.occupancyMs, costs.tableMs, downloadMs, scaleMs, total, totalWithScale);
      std::fflush(stdout);
    }
    std::printf("{\"bench\":\"hover_summary\",\"volume\":%d,\"width\":%d,\"height\":%d,\"cycles\":%d,"
                "\"total_ms_median\":%.2f,\"total_ms_p99\":%.2f,\"total_ms_max\":%.2f,\"frame_gpu_ms_median\":%.3f,\"device\":\"%s\",\"ray_caster\":\"%s\",\"step_mm\":%.4f,"
                "\"unit\":\"%s\",\"field_scale_ms_median\":%.2f,\"field_scale_ms_max\":%.2f,\"total_with_scale_ms_median\":%.2f,\"total_with_scale_ms_max\":%.2f}\n",
                o.hoverVolume, o.width, o.height, o.cycles, percentile(totals, 0.5), percentile(totals, 0.99), percentile(totals, 1.0),
                percentile(frameGpu, 0.5), ctx->description().c_str(), rayCasterName, render::effectiveStepMm(ds.volume.geometry, *settings),
                o.fieldUnit ? "field" : "size", percentile(scaleMsAll, 0.5), percentile(scaleMsAll, 1.0),
                percentile(totalsWithScale, 0.5), percentile(totalsWithScale, 1.0));
  }
  return 0;
}
