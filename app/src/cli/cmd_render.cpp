// anatomy-tutor render: one offscreen frame of a structure in one of the paper's modes, as PNG.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "cli_args.h"
#include "commands.h"
#include "data_paths.h"
#include "dataset_options.h"
#include "shown_dataset.h"
#include "render/gl/egl_context.h"
#include "render/gl/volume_renderer.h"
#include "render/derived_preset.h"
#include "render/overlay.h"
#include "render/preset.h"
#include "render/scene.h"
#include "render/volume_preset.h"
#include "volume/mask.h"
#include "volume/dataset_source.h"
#include "volume/png_image.h"
#include "render/field_scale.h"
#include "render/picture_scale.h"
#include "render/gradient_volume.h"
#include "wdt/wdt.h"
#include "printable_output.h"

namespace at::app {

namespace {

namespace fs = std::filesystem;

std::string formatUnit(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

std::string percent(double share) {
  char text[32];
  std::snprintf(text, sizeof text, "%.0f %%", 100 * share);
  return text;
}

const char* kUsage =
    "usage: anatomy-tutor render DATASET [STRUCTURE (--preset NAME | --mode MODE)] [--t T] [--size WxH]\n"
    "                            [--view NAME] [--clip NX,NY,NZ,D] [--backend cpu|cuda|auto] [--passes N]\n"
    "                            [--context F] [--margin F] [--presets DIR] [--labels FILE [--names NAMES.json]] [--series UID]\n"
    "                            [--no-overlays] [--db PATH] --out F.png\n"
    "  DATASET     phantom, phantom:N, skull, an imported dataset, or a volume file/folder (--labels: its label map,\n"
    "              --names: its label names, --series: the DICOM series where a folder holds several)\n"
    "  MODE        wdt | bare | unweighted | fuzzy | outline | lighting: the structure's shipped preset of that\n"
    "              mode, or one derived from the dataset's intensities where none is shipped\n"
    "  --preset    a preset id from the presets folder, or a path to a .json preset\n"
    "  --t         context blend 0..1 (overrides the preset)\n"
    "  --view      anterior, posterior, lateral_left, lateral_right, superior, inferior\n"
    "  --clip      plane n·p = d in LPS mm; the side the normal points to is cut away\n"
    "  --context   how far the context reaches, as a multiple of the structure's own context radius\n"
    "              (from its size; default 1)\n"
    "  --margin    the structure's extent (the volume's without STRUCTURE) times this fills the view\n"
    "              (default 1.6)\n"
    "  --no-overlays  leave out the orientation marker (patient axes L/R, A/P, S/I, bottom left) and\n"
    "              the scale bar in millimetres (bottom right)\n"
    "  --presets   presets folder (default: the installed presets, or $AT_DATA_DIR/presets)\n"
    "  --intensity auto|hu|plain: how a volume file's values are read (CT in HU, or plain intensities)\n"
    "Without STRUCTURE the whole volume is rendered with a data transfer function derived from the\n"
    "data (CT: its edges, skin and organ walls as translucent flesh and bone white; plain intensities\n"
    "such as a µCT: a ramp over the window of their histogram), or the data TF of --preset; datasets\n"
    "with no labels render so.\n";


Result<std::array<float, 4>> parseClip(const std::string& text) {
  std::array<float, 4> c{};
  std::stringstream ss(text);
  std::string part;
  int n = 0;
  while (std::getline(ss, part, ',')) {
    if (n >= 4) break;
    char* end = nullptr;
    c[std::size_t(n)] = std::strtof(part.c_str(), &end);
    if (part.empty() || *end != '\0') return fail("option --clip: '" + text + "' is not NX,NY,NZ,D");
    ++n;
  }
  if (n != 4 || std::getline(ss, part, ',')) return fail("option --clip: '" + text + "' is not NX,NY,NZ,D");
  return c;
}


}  // namespace

int runRender(const Argv& argv) {
  auto args = cli::Args::parse(argv,
                               withDatasetOptions({"preset", "mode", "t", "size", "view", "clip", "backend", "passes",
                                                   "context", "margin", "presets", "out"}),
                               withDatasetFlags({"no-overlays"}));
  if (!args) return reportError("render: " + args.error().message, 2);
  if (args->has("help")) {
    terminalPrintf("%s", kUsage);
    return 0;
  }
  const bool wholeVolume = args->positional().size() == 1;
  if (args->positional().empty() || args->positional().size() > 2)
    return reportError("render: expected DATASET [STRUCTURE] (see --help)", 2);
  if (wholeVolume && args->has("mode"))
    return reportError("render: --mode needs a STRUCTURE (the whole volume is drawn with its data TF)", 2);
  if (!wholeVolume && args->has("preset") == args->has("mode"))
    return reportError("render: give exactly one of --preset NAME or --mode MODE", 2);
  const auto out = args->value("out");
  if (!out) return reportError("render: --out F.png is required", 2);

  const render::PresetLibrary library(args->has("presets") ? fs::path(*args->value("presets")) : defaultPresetsDir());
  // The CT table, headrest and other objects outside the body are no context (shown_dataset.h).
  auto shown = openDatasetForViewing(datasetRequestFrom(*args, args->positional()[0]));
  if (!shown) return reportError("render: " + shown.error().message);
  reportDatasetWarnings(shown->dataset);
  Dataset* dataset = &shown->dataset;
  const Structure* structure = wholeVolume ? nullptr : dataset->findStructure(args->positional()[1]);
  if (!wholeVolume && !structure) return reportError("render: " + unknownStructureMessage(*dataset, args->positional()[1]));

  const render::IntensityLevels& levels = shown->levels;
  Result<render::Preset> preset = fail("no preset");
  if (wholeVolume) {
    preset = render::wholeVolumePreset(dataset->intensity, dataset->volume.geometry);
    if (auto name = args->value("preset")) {  // its data TF over the whole volume
      auto chosen = (name->size() > 5 && name->substr(name->size() - 5) == ".json") ? render::loadPreset(*name)
                                                                                    : library.load(*name);
      if (!chosen) return reportError("render: " + chosen.error().message);
      preset->dataTf = chosen->dataTf;
      preset->name = chosen->name;
      preset->id = chosen->id;
    }
  } else if (auto name = args->value("preset")) {
    preset = (name->size() > 5 && name->substr(name->size() - 5) == ".json") ? render::loadPreset(*name)
                                                                              : library.load(*name);
  } else {
    auto mode = render::parseRenderMode(*args->value("mode"));
    if (!mode) return reportError("render: --mode: " + mode.error().message, 2);
    preset = render::presetOrDerived(library, structure->id, *mode, levels);
  }
  if (!preset) return reportError("render: " + preset.error().message);
  auto t = args->number("t", preset->t);
  if (!t || *t < 0 || *t > 1) return reportError("render: option --t must be a number in 0..1", 2);
  preset->t = float(*t);

  render::ViewRequest request;
  if (auto size = args->size()) {
    request.width = size->width;
    request.height = size->height;
  }
  if (auto v = args->value("view")) request.view = *v;
  if (auto c = args->value("clip")) {
    auto clip = parseClip(*c);
    if (!clip) return reportError("render: " + clip.error().message, 2);
    request.clip = *clip;
  }
  auto context = args->number("context", request.contextScale);
  if (!context || *context <= 0) return reportError("render: option --context must be a positive number", 2);
  request.contextScale = *context;
  if (wholeVolume) request.contextScale = 1.0;
  auto margin = args->number("margin", request.margin);
  if (!margin || *margin < 1 || *margin > 100) return reportError("render: option --margin must be a number in 1..100", 2);
  request.margin = *margin;
  auto frame = wholeVolume ? Result<render::StructureFrame>(render::volumeFrame(dataset->volume.geometry))
                           : render::structureFrame(dataset->labels, structure->label);
  if (!frame) return reportError("render: " + structure->id + ": " + frame.error().message);
  auto settings = render::settingsFor(*preset, *frame, request);
  if (!settings) return reportError("render: " + settings.error().message, 2);
  settings->background = {0.04f, 0.04f, 0.05f, 1.0f};
  if (wholeVolume && !args->has("preset")) settings->opacityRefMm = render::wholeVolumeRefMm(dataset->volume.geometry);

  std::optional<DistanceField> field;
  // The volume's gradients, computed once for the renderer and, in fuzzy and lighting, the picture their
  // scale is judged on (render/picture_scale.h).
  std::optional<render::GradientVolume> gradients;
  std::string unitNote;
  double wdtMs = 0;
  std::string wdtDevice = "none";
  if (wholeVolume) {
    field = DistanceField{render::neutralField(dataset->volume.geometry), 1};
  } else if (render::modeNeedsField(preset->mode)) {
    auto passes = args->integer("passes", 2);
    if (!passes || *passes < 1) return reportError("render: option --passes must be a positive integer", 2);
    auto params = render::wdtParamsFor(*preset, *passes);
    if (!params) return reportError("render: " + params.error().message);
    applyDatasetWindow(*dataset, params->huMin, params->huMax, false, params->weight != WeightRule::Uniform);
    auto backend = parseBackend(args->valueOr("backend", "auto"));
    if (!backend) return reportError("render: --backend: " + backend.error().message, 2);
    params->backend = *backend;
    auto wdt = computeWdt(dataset->volume, structureMask(dataset->labels, structure->label), *params);
    if (!wdt) return reportError("render: " + wdt.error().message);
    if (!wdt->stats.warning.empty()) terminalFprintf(stderr, "anatomy-tutor: render: %s\n", wdt->stats.warning.c_str());
    wdtMs = wdt->stats.msTotal;
    wdtDevice = wdt->stats.device;
    field = std::move(wdt->field);
    // The distance unit from the field and the data (render/field_scale.h), times --context.
    render::PictureInputs picture{&dataset->labels, structure->label, nullptr};
    if (render::judgedOnPicture(preset->mode)) {
      gradients = render::computeGradientVolume(dataset->volume);
      picture.gradients = &*gradients;
    }
    const auto scaleStart = std::chrono::steady_clock::now();
    const render::FieldScale scale =
        render::applyFieldScale(*settings, field->distances, dataset->volume, nullptr, *frame, request, &picture);
    const double scaleMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - scaleStart).count();
    unitNote = "; distance unit " + formatUnit(settings->distanceUnit) +
               (scale.distanceOffset > 0 ? ", offset " + formatUnit(scale.distanceOffset) : std::string()) +
               (scale.fromPicture && scale.pictureAroundX > 0
                    ? " (chosen by the picture: the around bone's median D " + formatUnit(scale.aroundQuantileD) + " at x " +
                          formatUnit(scale.pictureAroundX) + "; colour on " + percent(scale.pictureNear) + " next to it, " +
                          percent(scale.pictureFar) + " far from it)"
                : scale.fromPicture && scale.pictureStretch != 1
                    ? " (stretched × " + formatUnit(scale.pictureStretch) + " by the picture: the band on " + percent(scale.pictureNear) +
                          " of the bone next to it, " + percent(scale.pictureFar) + " far from it)"
                : scale.fromPicture && scale.pictureShrink != 1 && preset->mode == render::RenderMode::Fuzzy
                    ? " (shrunk × " + formatUnit(scale.pictureShrink) + " by the picture: colour on " + percent(scale.pictureNear) +
                          " next to it, " + percent(scale.pictureFar) + " far from it)"
                : scale.fromNeighbours ? " (median bone D next to it in view " + formatUnit(scale.nearRingD) + ", far from it " + formatUnit(scale.farRingD) + ")"
                : scale.derived ? std::string(scale.fromSeen ? " (median seen bone D " : " (median bone D ") + formatUnit(scale.quantileD) + ", 90 % " + formatUnit(scale.farQuantileD) +
                                   (scale.cappedByRays ? "; capped: rays' nearest bone beyond D " + formatUnit(scale.drawnLimitD) + " fades" : std::string()) +
                                   "; by size " +
                                   formatUnit(render::distanceUnitFor(*frame, request.contextScale)) + ")"
                              : " (from its size)") +
               (scale.fromPicture && scale.lightingReach != 1
                    ? "; light reach × " + formatUnit(scale.lightingReach) + " (chosen by the picture: light on " +
                          percent(scale.pictureNear) + " next to it, " + percent(scale.pictureFar) + " far from it)"
                : scale.pictureJudged && !scale.fromPicture
                    ? "; picture: colour on " + percent(scale.pictureNear) + " next to it, " + percent(scale.pictureFar) + " far from it"
                    : std::string()) +
               ", " + formatUnit(scaleMs) + " ms";
  }

  auto context3d = render::gl::EglContext::create();
  if (!context3d) return reportError("render: " + context3d.error().message);
  auto renderer = render::gl::VolumeRenderer::create();
  if (!renderer) return reportError("render: " + renderer.error().message);
  if (auto st = gradients ? renderer->setVolume(dataset->volume, dataset->labels, *gradients)
                           : renderer->setVolume(dataset->volume, dataset->labels);
      !st)
    return reportError("render: " + st.error().message);
  if (field)
    if (auto st = renderer->setField(field->distances); !st) return reportError("render: " + st.error().message);
  renderer->setSelected(structure ? structure->label : 0);
  const auto start = std::chrono::steady_clock::now();
  auto image = renderer->render(*settings);
  if (!image) return reportError("render: " + image.error().message);
  const double renderMs = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  RgbImage rgb = render::toRgb(*image);
  if (!args->has("no-overlays")) render::drawOverlays(rgb, settings->camera);
  if (auto st = writePng(*out, rgb); !st)
    return reportError("render: " + st.error().message);
  terminalPrintf("wrote %s (%s, %s, preset %s, %dx%d, t=%.2f%s; WDT %.0f ms on %s; render %.0f ms on %s)\n", out->c_str(),
              structure ? structure->id.c_str() : "whole volume", render::toString(preset->mode), preset->id.value_or("?").c_str(), image->width,
              image->height, double(preset->t), unitNote.c_str(), wdtMs, wdtDevice.c_str(), renderMs, context3d->description().c_str());
  return 0;
}

std::filesystem::path defaultPresetsDir() { return dataSubdirectory("presets"); }

}  // namespace at::app
