#include "terminal_views.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <sstream>

#include "commands.h"
#include "course_views.h"
#include "db/preset_store.h"
#include "dataset_resolver.h"
#include "shown_dataset.h"
#include "slice_marking.h"
#include "render/gl/egl_context.h"
#include "render/gl/volume_renderer.h"
#include "render/image.h"
#include "render/overlay.h"
#include "render/pick_bounds.h"
#include "render/scene.h"
#include "render/structure_pick.h"
#include "render/target_side.h"
#include "volume/dataset_source.h"
#include "volume/mask.h"
#include "volume/png_image.h"
#include "printable_output.h"

namespace at::app {

namespace fs = std::filesystem;

namespace {

constexpr int kWidth = kPictureWidth, kHeight = kPictureHeight;
constexpr int kSliceScale = 3;               // pixels per voxel side on slices

std::optional<std::array<int, 3>> voxelOf(const Geometry& g, const Vec3& pointMm) {
  const Vec3 ijk = g.patientToIndex(pointMm);
  const int i = int(std::lround(ijk[0])), j = int(std::lround(ijk[1])), k = int(std::lround(ijk[2]));
  if (!g.dims.contains(i, j, k)) return std::nullopt;
  return std::array<int, 3>{i, j, k};
}

// Rulers along the top and left edges (a tick every 10 pixels, longer every 50, numbered every
// 100) so that a student can read the pixel coordinates of a point with any image viewer.
void drawPixelRulers(RgbImage& image) {
  // 3×5 digits, one row per 3-bit line, top first.
  static constexpr std::uint8_t kDigits[10][5] = {{7, 5, 5, 5, 7}, {2, 6, 2, 2, 7}, {7, 1, 7, 4, 7}, {7, 1, 7, 1, 7},
                                                  {5, 5, 7, 1, 1}, {7, 4, 7, 1, 7}, {7, 4, 7, 5, 7}, {7, 1, 1, 1, 1},
                                                  {7, 5, 7, 5, 7}, {7, 5, 7, 1, 7}};
  const auto dot = [&](int x, int y) {
    if (x < 0 || y < 0 || x >= image.width || y >= image.height) return;
    std::uint8_t* p = image.pixel(x, y);
    p[0] = 255, p[1] = 235, p[2] = 60;
  };
  const auto number = [&](int value, int x, int y) {  // digits 2× scaled, left edge at x
    const std::string text = std::to_string(value);
    for (std::size_t d = 0; d < text.size(); ++d)
      for (int row = 0; row < 5; ++row)
        for (int col = 0; col < 3; ++col)
          if (kDigits[text[d] - '0'][row] & (4 >> col))
            for (int k = 0; k < 4; ++k) dot(x + int(d) * 8 + col * 2 + k % 2, y + row * 2 + k / 2);
  };
  for (int x = 0; x < image.width; x += 10) {
    const int length = x % 50 == 0 ? 6 : 3;
    for (int y = 0; y < length; ++y) dot(x, y);
    if (x % 100 == 0 && x > 0) number(x, x + 2, 7);
  }
  for (int y = 0; y < image.height; y += 10) {
    const int length = y % 50 == 0 ? 6 : 3;
    for (int x = 0; x < length; ++x) dot(x, y);
    if (y % 100 == 0 && y > 0) number(y, 7, y + 2);
  }
}

}  // namespace

TerminalViews::~TerminalViews() = default;

Result<std::unique_ptr<TerminalViews>> TerminalViews::create(db::Database& db, const std::string& datasetId,
                                                             fs::path dir, bool pictures) {
  std::unique_ptr<TerminalViews> v(new TerminalViews());
  const std::string name = datasetId == "phantom" ? "phantom:128" : datasetId;
  DatasetRequest request;
  request.name = name;
  request.database = &db;
  // As the render command and the desktop show it: the CT table and headrest left out.
  auto shown = openDatasetForViewing(request);
  if (!shown) return tl::unexpected(shown.error());
  v->dataset_ = std::move(shown->dataset);
  v->levels_ = shown->levels;
  v->presets_ = std::make_unique<render::PresetLibrary>(defaultPresetsDir());
  v->database_ = &db;
  if (!pictures) return v;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return fail(dir.string() + ": cannot create the folder for the pictures (" + ec.message() + ")");
  v->dir_ = std::move(dir);
  v->gradients_ = std::make_unique<render::GradientVolume>(render::computeGradientVolume(v->dataset_.volume));
  auto context = render::gl::EglContext::create();
  if (!context) return fail("offscreen rendering: " + context.error().message);
  v->context_ = std::make_unique<render::gl::EglContext>(std::move(*context));
  auto renderer = render::gl::VolumeRenderer::create();
  if (!renderer) return fail("offscreen rendering: " + renderer.error().message);
  v->renderer_ = std::make_unique<render::gl::VolumeRenderer>(std::move(*renderer));
  if (auto st = v->renderer_->setVolume(v->dataset_.volume, v->dataset_.labels, *v->gradients_); !st)
    return tl::unexpected(st.error());
  return v;
}

Result<render::Preset> TerminalViews::presetOf(const Structure& structure, const std::string& presetId) const {
  if (!presetId.empty()) {
    // The database's (an imported course's, a captured one) before the shipped library's.
    if (auto stored = db::findPreset(*database_, presetId); stored && *stored)
      if (auto preset = render::parsePreset((*stored)->json, "preset '" + presetId + "' (database)")) return preset;
    if (auto preset = presets_->load(presetId)) return preset;
  }
  return render::presetOrDerived(*presets_, structure.id, render::RenderMode::Wdt, levels_);
}

Result<const FloatVolume*> TerminalViews::fieldOf(const Structure& structure, const render::Preset& preset) {
  if (auto it = fields_.find(structure.id); it != fields_.end()) return &it->second;
  auto params = render::wdtParamsFor(preset);
  if (!params) return tl::unexpected(params.error());
  auto wdt = computeWdt(dataset_.volume, structureMask(dataset_.labels, structure.label), *params);
  if (!wdt) return tl::unexpected(withContext(structure.id, wdt.error()));
  FloatVolume field = wdt->field.downsample == 1 ? std::move(wdt->field.distances)
                                                 : upsampleField(wdt->field, dataset_.labels.geometry);
  return &fields_.emplace(structure.id, std::move(field)).first->second;
}

Result<render::RenderSettings> TerminalViews::settingsFor(const Structure& selected, const render::Preset& preset,
                                                          const lessons::QuestionScene& scene, const std::string& view,
                                                          int width, int height, double margin, const FloatVolume* field) {
  auto frame = render::structureFrame(dataset_.labels, selected.label);
  if (!frame) return fail(selected.id + ": " + frame.error().message);
  render::ViewRequest request;
  request.width = width;
  request.height = height;
  request.view = view;
  if (margin > 0) request.margin = margin;
  // The distance unit from the field on this very view, as the render command and the desktop set it.
  const render::PictureInputs picture{&dataset_.labels, selected.label, gradients_.get()};
  auto settings = stepViewSettings(preset, *frame, request, scene.camera, scene.clip, field, dataset_.volume, &picture);
  if (!settings) return tl::unexpected(settings.error());
  settings->background = {0.04f, 0.04f, 0.05f, 1.0f};
  return settings;
}

Result<TerminalPicture> TerminalViews::frame(const lessons::QuestionScene& scene, bool region,
                                             const std::optional<std::string>& visibleTarget) {
  if (!gradients_) gradients_ = std::make_unique<render::GradientVolume>(render::computeGradientVolume(dataset_.volume));
  const Structure* selected = dataset_.findStructure(scene.structure);
  if (!selected) return fail("the view's structure '" + scene.structure + "' is not in dataset '" + dataset_.id + "'");
  auto preset = presetOf(*selected, scene.presetId);
  if (!preset) return tl::unexpected(preset.error());
  const FloatVolume* field = nullptr;
  if (render::modeNeedsField(preset->mode)) {
    auto f = fieldOf(*selected, *preset);
    if (!f) return tl::unexpected(f.error());
    field = *f;
  }
  const render::TransferFunction2D table = render::shadingTable(*preset);
  auto mask = masks_.find(selected->label);
  if (mask == masks_.end()) mask = masks_.emplace(selected->label, render::selectedMask(dataset_.labels, selected->label)).first;
  render::SceneVolumes volumes{&dataset_.volume, &dataset_.labels, field, selected->label, gradients_.get(), &mask->second};

  const std::string ownView = lessons::toString(scene.view);
  auto sideSettings = [&](const std::string& view) -> Result<render::RenderSettings> {
    return settingsFor(*selected, *preset, scene, view, kWidth, kHeight, region ? kRegionMargin : 0, field);
  };
  // A step's free camera is the author's choice: kept even when the target does not show.
  const Structure* target = visibleTarget && !scene.camera ? dataset_.findStructure(*visibleTarget) : nullptr;
  std::optional<render::RenderSettings> chosen;  // the scene's own side unless another shows the target
  if (target) {
    auto side = render::firstSideShowingTarget(ownView, [&](const std::string& view) -> Result<bool> {
      auto settings = sideSettings(view);
      if (!settings) return tl::unexpected(settings.error());
      const bool shows = render::targetClickableAt(settings->camera, kWidth, kHeight, dataset_.labels, target->label, settings->clip,
                                                   [&](double x, double y) {
                                                     return render::pickStructure(volumes, *settings, table, x, y);
                                                   });
      if (shows) chosen = *settings;
      return shows;
    });
    if (!side) return tl::unexpected(side.error());
  }
  if (!chosen) {
    auto own = sideSettings(ownView);
    if (!own) return tl::unexpected(own.error());
    chosen = *own;
  }

  lastSettings_ = *chosen;
  lastTable_ = render::shadingTable(chosen->preset);  // built once: every pick on this view reads it
  lastSelected_ = selected->label;
  lastField_ = field;
  lastSlice_.reset();
  return TerminalPicture{"", kWidth, kHeight, false};
}

Result<TerminalPicture> TerminalViews::show(const lessons::QuestionScene& scene, const std::string& stem, bool region,
                                            const std::optional<std::string>& visibleTarget) {
  if (!renderer_) return fail("pictures are off");
  auto framed = frame(scene, region, visibleTarget);
  if (!framed) return framed;
  renderer_->setSelected(lastSelected_);
  if (lastField_) {
    if (auto st = renderer_->setField(*lastField_); !st) return tl::unexpected(st.error());
  } else {
    renderer_->clearField();
  }
  auto image = renderer_->render(*lastSettings_);
  if (!image) return tl::unexpected(image.error());
  const fs::path path = dir_ / (stem + ".png");
  RgbImage picture = render::toRgb(*image);
  render::drawOverlays(picture, lastSettings_->camera);  // orientation marker and scale bar
  drawPixelRulers(picture);
  if (auto st = writePng(path.string(), picture); !st) return tl::unexpected(st.error());
  framed->path = path.string();
  return framed;
}

std::optional<std::array<int, 4>> TerminalViews::pixelsThatCanPick(const std::string& targetId, double toleranceMm) {
  if (!lastSettings_) return std::nullopt;
  const Structure* target = dataset_.findStructure(targetId);
  if (!target) return std::nullopt;
  const FloatVolume* field = nullptr;
  if (toleranceMm > 0) {  // the distances picks read: the target's field under its own preset
    auto preset = presetOf(*target, "");
    if (!preset) return std::nullopt;
    auto f = fieldOf(*target, *preset);
    if (!f) return std::nullopt;
    field = *f;
  }
  return render::pixelsThatCanPick(dataset_.labels, target->label, field, toleranceMm, *lastSettings_);
}

namespace {

// FNV-1a over 64-bit words (the tail bytes one by one): a fingerprint, not a cryptographic hash.
std::uint64_t mixBytes(std::uint64_t h, const void* data, std::size_t size) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  std::size_t i = 0;
  for (; i + 8 <= size; i += 8) {
    std::uint64_t word;
    std::memcpy(&word, bytes + i, 8);
    h = (h ^ word) * 0x100000001b3ull;
    h ^= h >> 29;
  }
  for (; i < size; ++i) h = (h ^ bytes[i]) * 0x100000001b3ull;
  return h;
}

}  // namespace

std::string TerminalViews::lastViewId() {
  if (!lastSettings_) return "";
  if (!dataDigest_) {
    std::uint64_t h = 0xcbf29ce484222325ull;
    h = mixBytes(h, dataset_.volume.voxels.data(), dataset_.volume.voxels.size() * sizeof(std::int16_t));
    h = mixBytes(h, dataset_.labels.voxels.data(), dataset_.labels.voxels.size() * sizeof(std::uint16_t));
    const auto& g = dataset_.labels.geometry;
    char grid[400];
    std::snprintf(grid, sizeof grid, "%s|%.5f %.5f %.5f|%.4f %.4f %.4f|%.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f",
                  g.dims.toString().c_str(), g.spacingMm[0], g.spacingMm[1], g.spacingMm[2], g.originMm[0],
                  g.originMm[1], g.originMm[2], g.direction.m[0][0], g.direction.m[0][1], g.direction.m[0][2],
                  g.direction.m[1][0], g.direction.m[1][1], g.direction.m[1][2], g.direction.m[2][0],
                  g.direction.m[2][1], g.direction.m[2][2]);
    dataDigest_ = mixBytes(h, grid, std::strlen(grid));
  }
  // Everything a pick on the view depends on, as text rounded well below a pixel's size.
  const render::RenderSettings& r = *lastSettings_;
  const render::Camera& c = r.camera;
  const Vec3 eye = c.eye();
  char text[640];
  std::snprintf(text, sizeof text,
                "%dx%d|%.4f %.4f %.4f|%.4f %.4f %.4f|%.4f %.4f %.4f|%.4f %.4f %d|%s|%.5f %.5f %.5f %.5f|%d %d %d|%u",
                r.width, r.height, eye[0], eye[1], eye[2], c.target[0], c.target[1], c.target[2], c.up()[0], c.up()[1],
                c.up()[2], c.distanceMm, c.fovYDeg, int(c.orthographic),
                r.clip ? (std::to_string(r.clip->normal[0]) + " " + std::to_string(r.clip->normal[1]) + " " +
                          std::to_string(r.clip->normal[2]) + " " + std::to_string(r.clip->d)).c_str()
                       : "-",
                r.stepMm, r.opacityRefMm, r.distanceUnit, r.distanceOffset, int(r.jitter), int(r.shading),
                r.tableSize, unsigned(lastSelected_));
  std::uint64_t h = mixBytes(*dataDigest_, text, std::strlen(text));
  const std::string preset = render::presetToJson(r.preset);
  h = mixBytes(h, preset.data(), preset.size());
  char id[40];
  std::snprintf(id, sizeof id, "%dx%d-%016llx", r.width, r.height, (unsigned long long)h);
  return id;
}

Result<TerminalPicture> TerminalViews::showSlice(const std::string& targetId, const std::string& stem, bool highlight) {
  if (!renderer_) return fail("pictures are off");
  const Structure* target = dataset_.findStructure(targetId);
  if (!target) return fail("structure '" + targetId + "' is not in dataset '" + dataset_.id + "'");
  const auto frame = render::structureFrame(dataset_.labels, target->label);
  if (!frame) return fail("structure '" + targetId + "' has no voxels in dataset '" + dataset_.id + "'");
  SliceRequest request = anchorSliceRequest(dataset_.labels.geometry, frame->anchorMm, kSliceScale);  // patient orientation
  const std::vector<Structure> only{*target};
  if (highlight) request.labelAlpha = 0.65;
  auto image = highlight ? renderSlice(dataset_.volume, &dataset_.labels, only, request)
                         : renderSlice(dataset_.volume, nullptr, dataset_.structures, request);  // no labels
  if (!image) return tl::unexpected(image.error());
  if (highlight) frameStructureOnSlice(*image, dataset_.labels, request, target->label, 4 * kSliceScale);
  drawPixelRulers(*image);
  drawSliceEdgeLetters(*image, *request.layout);
  const fs::path path = dir_ / (stem + ".png");
  if (auto st = writePng(path.string(), *image); !st) return tl::unexpected(st.error());
  lastSlice_ = request;
  lastSettings_.reset();
  return TerminalPicture{path.string(), image->width, image->height, true};
}

namespace {

// The pick of a point (or of nothing) on `label`, with its distance read from `targetField`.
quiz::Pick pickOf(const Dataset& dataset, const std::optional<Vec3>& pointMm, std::uint16_t label,
                  const FloatVolume* targetField) {
  quiz::Pick pick;
  if (const Structure* s = dataset.findStructureByLabel(label)) pick.structure = s->id;
  if (pointMm && targetField)
    if (const auto v = voxelOf(targetField->geometry, *pointMm))
      pick.distanceMm = targetField->at((*v)[0], (*v)[1], (*v)[2]);
  return pick;
}

}  // namespace

const FloatVolume* TerminalViews::pickFieldOf(const Structure& target) {
  if (auto known = fields_.find(target.id); known != fields_.end()) return &known->second;
  if (auto preset = presetOf(target, ""); preset)
    if (auto computed = fieldOf(target, *preset)) return *computed;
  return nullptr;
}

Result<PixelPicks> TerminalViews::pixelPicks(const std::string& target) {
  if (!lastSlice_ && !lastSettings_) return fail("there is no picture to pick on (pictures are off); give a point as mm X Y Z");
  PixelPicks picks;
  picks.dataset_ = &dataset_;
  picks.target_ = dataset_.findStructure(target);
  if (picks.target_) picks.targetField_ = pickFieldOf(*picks.target_);
  if (lastSlice_) {
    picks.slice_ = &*lastSlice_;
    return picks;
  }
  const auto mask = masks_.find(lastSelected_);  // made by frame()
  picks.settings_ = &*lastSettings_;
  picks.table_ = &*lastTable_;
  picks.volumes_ = render::SceneVolumes{&dataset_.volume, &dataset_.labels, lastField_, lastSelected_, gradients_.get(),
                                        mask == masks_.end() ? nullptr : &mask->second};
  return picks;
}

Result<quiz::Pick> PixelPicks::at(double x, double y) const {
  if (slice_) {
    const auto ijk = sliceVoxelAt(dataset_->labels.dims(), *slice_, x, y);
    if (!ijk) return fail("the pixel (" + std::to_string(int(x)) + ", " + std::to_string(int(y)) + ") is outside the slice");
    const Vec3 p = dataset_->labels.geometry.indexToPatient({double((*ijk)[0]), double((*ijk)[1]), double((*ijk)[2])});
    return pickOf(*dataset_, p, dataset_->labels.at((*ijk)[0], (*ijk)[1], (*ijk)[2]), targetField_);
  }
  if (x < 0 || y < 0 || x >= settings_->width || y >= settings_->height)
    return fail("the pixel (" + std::to_string(int(x)) + ", " + std::to_string(int(y)) + ") is outside the " +
                std::to_string(settings_->width) + "×" + std::to_string(settings_->height) + " picture");
  const render::PickResult hit = render::pickStructure(volumes_, *settings_, *table_, x, y);
  return pickOf(*dataset_, hit.hit ? std::optional<Vec3>(hit.pointMm) : std::nullopt, hit.hit ? hit.label : 0,
                targetField_);
}

Result<quiz::Pick> TerminalViews::pickPixel(double x, double y, const std::string& target) {
  auto picks = pixelPicks(target);
  if (!picks) return tl::unexpected(picks.error());
  return picks->at(x, y);
}

Result<quiz::Pick> TerminalViews::pickPointMm(const Vec3& pointMm, const std::string& target) {
  const auto v = voxelOf(dataset_.labels.geometry, pointMm);
  const Structure* t = dataset_.findStructure(target);
  return pickOf(dataset_, pointMm, v ? dataset_.labels.at((*v)[0], (*v)[1], (*v)[2]) : 0, t ? pickFieldOf(*t) : nullptr);
}

std::unique_ptr<TerminalViews> openTerminalViews(db::Database& db, const std::string& datasetId,
                                                 const std::optional<std::string>& dir, bool off) {
  const fs::path folder = dir.value_or("anatomy-tutor-views");
  if (!off) {
    auto views = TerminalViews::create(db, datasetId, folder, true);
    if (views) return std::move(*views);
    terminalPrintf("(no pictures: %s; locate answers take a point as mm X Y Z)\n", views.error().message.c_str());
  }
  auto views = TerminalViews::create(db, datasetId, folder, false);
  if (!views) {
    terminalPrintf("(locate answers need dataset '%s', which does not load: %s)\n", datasetId.c_str(),
                views.error().message.c_str());
    return nullptr;
  }
  return std::move(*views);
}

Result<PickInput> parsePickInput(const std::string& raw) {
  std::string text = raw;
  for (char& c : text)
    if (c == ',' || c == '(' || c == ')') c = ' ';
  std::istringstream in(text);
  std::string first;
  in >> first;
  const auto explain = [&] {
    return fail("'" + raw + "' is not a pick: type the pixel where it is in the picture as x y (e.g. 180 135), "
                "or a point in millimetres as mm X Y Z");
  };
  std::vector<double> numbers;
  const bool mm = first == "mm";
  if (!mm) {
    in.clear();
    in.str(text);
  }
  for (std::string word; in >> word;) {
    char* end = nullptr;
    const double v = std::strtod(word.c_str(), &end);
    if (word.empty() || *end != '\0' || !std::isfinite(v)) return explain();
    numbers.push_back(v);
  }
  PickInput input;
  if (mm && numbers.size() == 3) input.pointMm = Vec3{numbers[0], numbers[1], numbers[2]};
  else if (!mm && numbers.size() == 2) input.pixel = std::array<double, 2>{numbers[0], numbers[1]};
  else return explain();
  return input;
}

}  // namespace at::app
