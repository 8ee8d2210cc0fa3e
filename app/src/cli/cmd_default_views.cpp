// `anatomy-tutor` with no display: the default lesson's first views written as PNG files through
// the offscreen renderer (EGL), instead of the desktop app.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

#include "commands.h"
#include "course_views.h"
#include "render/gradient_volume.h"
#include "dataset_resolver.h"
#include "shown_dataset.h"
#include "render/gl/egl_context.h"
#include "render/gl/volume_renderer.h"
#include "render/scene.h"
#include "volume/dataset_source.h"
#include "volume/known_scans.h"
#include "volume/mask.h"
#include "volume/png_image.h"
#include "wdt/wdt.h"
#include "printable_output.h"

namespace at::app {

namespace fs = std::filesystem;

// The first views only: each costs a field and a software-GL frame.
constexpr int kFallbackViews = 3;

int writeDefaultViews(const fs::path& outDir, const std::string& courseId) {
  const auto start = std::chrono::steady_clock::now();
  auto course = loadStartCourse(courseId);
  if (!course) return reportError(course.error().message);
  const auto views = firstLessonViews(*course);
  if (views.empty()) return reportError("course '" + course->id + "': its first lesson has no views to show");
  // The phantom at 128³ (0.4 mm voxels): same anatomy, an eighth of the voxels.
  const std::string datasetName = course->datasetId == "phantom" ? "phantom:128" : course->datasetId;
  if (!isBuiltinDatasetName(datasetName) && !findKnownScan(datasetName))
    return reportError("course '" + course->id + "': dataset '" + course->datasetId +
                       "' is not built in; open it on a display with `anatomy-tutor desktop`");
  DatasetRequest request;  // a built-in name, or a known scan with the labels set-up grew for it
  request.name = datasetName;
  auto shown = openDatasetForViewing(request);  // the CT table and headrest left out, as everywhere
  if (!shown) return reportError(shown.error().message);
  Dataset* dataset = &shown->dataset;
  auto context = render::gl::EglContext::create();
  if (!context) return reportError("offscreen rendering: " + context.error().message);
  auto renderer = render::gl::VolumeRenderer::create();
  if (!renderer) return reportError("offscreen rendering: " + renderer.error().message);
  // The gradients once, for the renderer and for the fuzzy and lighting steps' scales (render/picture_scale.h).
  const render::GradientVolume gradients = render::computeGradientVolume(dataset->volume);
  if (auto st = renderer->setVolume(dataset->volume, dataset->labels, gradients); !st) return reportError(st.error().message);
  const render::IntensityLevels& levels = shown->levels;

  std::error_code ec;
  fs::create_directories(outDir, ec);
  if (ec) return reportError(outDir.string() + ": cannot create the folder (" + ec.message() + ")");
  const render::PresetLibrary library(defaultPresetsDir());
  int index = 0;
  for (const lessons::ShowStep& step : views) {
    if (index == kFallbackViews) break;
    ++index;
    const Structure* structure = dataset->findStructure(step.structure);
    if (!structure) return reportError("course step " + std::to_string(index) + ": no structure '" + step.structure + "'");
    auto preset = presetForStep(library, structure->id, step.presetId, levels);
    if (!preset) return reportError(preset.error().message);
    auto frame = render::structureFrame(dataset->labels, structure->label);
    if (!frame) return reportError(structure->id + ": " + frame.error().message);
    render::ViewRequest request;
    request.width = 360;  // small: software GL on two cores renders about 10⁵ rays per second
    request.height = 270;
    request.view = lessons::toString(step.view);
    std::optional<FloatVolume> field;
    if (render::modeNeedsField(preset->mode)) {
      auto params = render::wdtParamsFor(*preset);
      if (!params) return reportError(params.error().message);
      auto wdt = computeWdt(dataset->volume, structureMask(dataset->labels, structure->label), *params);
      if (!wdt) return reportError(structure->id + ": " + wdt.error().message);
      field = std::move(wdt->field.distances);
    }
    // Framed, placed and scaled as play and the desktop show the step (course_views.h).
    const render::PictureInputs picture{&dataset->labels, structure->label, &gradients};
    auto settings = stepViewSettings(*preset, *frame, request, step.camera, step.clip, field ? &*field : nullptr,
                                     dataset->volume, &picture);
    if (!settings) return reportError(settings.error().message);
    settings->background = {0.04f, 0.04f, 0.05f, 1.0f};
    renderer->setSelected(structure->label);
    if (field) {
      if (auto st = renderer->setField(*field); !st) return reportError(st.error().message);
    } else {
      renderer->clearField();
    }
    auto image = renderer->render(*settings);
    if (!image) return reportError(image.error().message);
    char name[128];
    std::snprintf(name, sizeof name, "%02d_%s_%s.png", index, structure->id.c_str(), render::toString(preset->mode));
    const fs::path out = outDir / name;
    if (auto st = writePng(out.string(), render::toRgb(*image)); !st) return reportError(st.error().message);
    terminalPrintf("wrote %s (%s, %s view)\n", out.string().c_str(), rowCell(step.title).c_str(), lessons::toString(step.view));
  }
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  terminalPrintf("%d views of '%s' in %.1f s (%s)\n", index, rowCell(course->lessons.front().title).c_str(), s,
              context->description().c_str());
  return 0;
}

}  // namespace at::app
