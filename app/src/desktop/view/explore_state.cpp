#include "view/explore_state.h"

#include <algorithm>
#include <cmath>

#include "course_views.h"
#include "render/volume_preset.h"

namespace at::app {

ExploreState::ExploreState(const render::PresetLibrary& library, MessageSink messages)
    : library_(library), messages_(std::move(messages)) {}

Status ExploreState::setDataset(const Dataset& dataset, const std::string& startStructure, const std::string& startPreset) {
  std::map<std::uint16_t, render::StructureFrame> frames;
  for (const Structure& s : dataset.structures)
    if (auto frame = render::structureFrame(dataset.labels, s.label)) frames[s.label] = *frame;
  dataset_ = &dataset;
  levels_ = render::summariseIntensities(dataset.volume);
  frames_ = std::move(frames);
  wholeVolume_ = frames_.empty();
  volumeFrame_ = render::volumeFrame(dataset.volume.geometry);
  bySystem_.clear();
  presets_.clear();
  override_.reset();
  hovered_ = 0;
  selected_ = 0;
  fieldLabel_ = 0;
  fieldKey_.clear();
  clip_.offsetMm = 0;
  if (wholeVolume_) {  // the data TF alone: WDT mode at t = 1 over a neutral field
    bare_ = false;
    t_ = 1.0f;
    changed();
    return {};
  }
  rebuildBrowser();
  const Structure* start = startStructure.empty() ? nullptr : dataset.findStructure(startStructure);
  // The start preset belongs to the start structure (a course's first view): another dataset's
  // first structure gets its own preset — shipped for its id, else derived from this data — never
  // the course structure's (the phantom's cochlea window on a µCT or MR shows nothing).
  std::string preset = startPreset;
  if (!start || !frames_.count(start->label)) {
    start = dataset.findStructureByLabel(frames_.begin()->first);
    preset.clear();
  }
  startOn(*start, preset);
  changed();
  return {};
}

void ExploreState::rebuildBrowser() {
  bySystem_.clear();
  for (const Structure& s : dataset_->structures) {
    if (!frames_.count(s.label)) continue;  // a named label with no voxels: not shown in the browser
    const std::string system = s.system.empty() ? std::string("other") : s.system;
    auto it = std::find_if(bySystem_.begin(), bySystem_.end(), [&](const auto& g) { return g.first == system; });
    if (it == bySystem_.end()) it = bySystem_.insert(bySystem_.end(), {system, {}});
    it->second.push_back(&s);
  }
}

void ExploreState::startOn(const Structure& structure, const std::string& presetId) {
  selected_ = structure.label;
  if (auto preset = presetForStep(library_, structure.id, presetId, levels_)) usePreset(structure.label, *preset, preset->t);
  else messages_(preset.error().message);
}

void ExploreState::labelsEdited(const std::vector<std::uint16_t>& edited, std::uint16_t current,
                                const std::optional<std::array<int, 6>>& editBox) {
  const Dataset& dataset = *dataset_;
  for (std::uint16_t label : edited) {
    presets_.erase({label, false});
    presets_.erase({label, true});
    const auto old = frames_.find(label);
    if (!editBox) continue;  // no voxel changed (a rename, a colour): the frame stands
    // The label's voxels now lie in its old box or in the edited one: only those are read (a
    // brush stroke costs its own box, not the whole map, on the UI thread).
    std::array<int, 6> box = *editBox;
    if (old != frames_.end())
      for (std::size_t a = 0; a < 3; ++a) {
        box[a] = std::min(box[a], old->second.voxelBox[a]);
        box[a + 3] = std::max(box[a + 3], old->second.voxelBox[a + 3]);
      }
    frames_.erase(label);
    if (label != 0 && dataset.findStructureByLabel(label))
      if (auto frame = render::structureFrame(dataset.labels, label, box)) frames_[label] = *frame;
  }
  for (auto it = frames_.begin(); it != frames_.end();)  // deleted structures
    it = dataset.findStructureByLabel(it->first) ? std::next(it) : frames_.erase(it);
  const bool wasWhole = std::exchange(wholeVolume_, frames_.empty());
  rebuildBrowser();
  if (wholeVolume_ != wasWhole) {  // the other mode's presets
    presets_.clear();
    override_.reset();
  }
  if (hovered_ && !frames_.count(hovered_)) hovered_ = 0;
  if (fieldLabel_ && !frames_.count(fieldLabel_)) {
    fieldLabel_ = 0;
    fieldKey_.clear();
  }
  if (wholeVolume_) {
    selected_ = 0;
    bare_ = false;
    t_ = 1.0f;
  } else {
    const bool currentEdited = std::find(edited.begin(), edited.end(), current) != edited.end();
    std::uint16_t next = currentEdited && frames_.count(current) ? current : selected_;
    if (!frames_.count(next)) next = frames_.begin()->first;
    if (wasWhole) startOn(*dataset.findStructureByLabel(next), "");
    else selected_ = next;
  }
  changed();
}

const render::StructureFrame* ExploreState::frameOf(std::uint16_t label) const {
  if (wholeVolume_) return label == 0 ? &volumeFrame_ : nullptr;
  auto it = frames_.find(label);
  return it == frames_.end() ? nullptr : &it->second;
}

const render::Preset& ExploreState::presetOf(std::uint16_t label, bool bare) const {
  const auto key = std::make_pair(label, bare);
  if (auto it = presets_.find(key); it != presets_.end()) return it->second;
  if (wholeVolume_)
    return presets_.emplace(key, render::wholeVolumePreset(dataset_->intensity, dataset_->volume.geometry)).first->second;
  render::Preset preset;
  const Structure* s = dataset_ ? dataset_->findStructureByLabel(label) : nullptr;
  const render::RenderMode mode = bare ? render::RenderMode::Bare : render::RenderMode::Wdt;
  auto loaded = s ? render::presetOrDerived(library_, s->id, mode, levels_) : Result<render::Preset>(fail("no structure"));
  if (loaded) {
    preset = *loaded;
  } else {
    messages_("presets: " + loaded.error().message + " (using the built-in default)");
    preset.mode = mode;
  }
  return presets_.emplace(key, preset).first->second;
}

render::Preset ExploreState::presetInMode(std::uint16_t label, render::RenderMode mode) const {
  const render::Preset& cached = presetOf(label, mode == render::RenderMode::Bare);
  if (cached.mode == mode) return cached;
  const Structure* s = dataset_ ? dataset_->findStructureByLabel(label) : nullptr;
  if (wholeVolume_ || !s) {
    render::Preset p = cached;
    p.mode = mode;
    return p;
  }
  auto loaded = render::presetOrDerived(library_, s->id, mode, levels_);
  if (loaded) return *loaded;
  messages_("presets: " + loaded.error().message + " (using the preset derived from the dataset)");
  return render::derivedPreset(levels_, mode, s->id);
}

std::uint16_t ExploreState::displayLabel() const {
  // Field modes keep the structure whose field is on screen until the hovered one's arrives.
  return bare_ ? shownLabel() : (fieldLabel_ ? fieldLabel_ : shownLabel());
}

ExploreState::Shown ExploreState::shown() const {
  Shown s;
  s.label = displayLabel();
  const bool noField = !wholeVolume_ && (bare_ || fieldLabel_ == 0);  // whole volume: its neutral field
  if (override_) {
    s.preset = *override_;
  } else {
    s.preset = presetOf(s.label, noField);  // before any field: the structure's bare preset
    s.preset.t = t_;
  }
  if (noField) s.preset.mode = render::RenderMode::Bare;
  return s;
}

std::optional<WdtParams> ExploreState::fieldParams(std::uint16_t label) const {
  auto params = render::wdtParamsFor(override_ ? *override_ : presetOf(label, false));
  if (!params) return std::nullopt;
  return *params;
}

const render::Preset& ExploreState::pickPreset() const { return presetOf(fieldLabel_ ? fieldLabel_ : shownLabel(), false); }

std::optional<render::ClipPlane> ExploreState::clipPlane() const {
  if (!clip_.on) return std::nullopt;
  Vec3 n{0, 0, 0};
  n[std::size_t(clip_.axis)] = clip_.flip ? -1 : 1;
  return render::ClipPlane{n, dot(n, camera_.target) + double(clip_.offsetMm)};
}

template <class F>
bool ExploreState::changeShown(F&& change) {
  const std::uint16_t before = displayLabel();
  const bool changedSomething = change();
  if (!changedSomething) return false;
  ++activity_;
  if (displayLabel() != before) ++revision_;
  return true;
}

bool ExploreState::select(std::uint16_t label) {
  if (!frames_.count(label)) return false;
  changeShown([&] { return std::exchange(selected_, label) != label; });
  return true;
}

bool ExploreState::setHovered(std::uint16_t label) {
  return changeShown([&] { return std::exchange(hovered_, label) != label; });
}

bool ExploreState::setBare(bool bare) {
  if (bare == bare_ || (bare && wholeVolume_)) return false;  // bare shows a structure alone
  bare_ = bare;
  changed();
  return true;
}

bool ExploreState::setT(float t) {
  t = std::clamp(t, 0.0f, 1.0f);
  if (t == t_) return false;
  t_ = t;
  changed();
  return true;
}

Status ExploreState::setView(const std::string& name, int width, int height, std::uint16_t alsoInView) {
  const std::uint16_t label = shownLabel();
  const render::StructureFrame* frame = frameOf(label);
  if (!frame) return {};
  std::optional<render::StructureFrame> both;
  if (const render::StructureFrame* other = alsoInView != label ? frameOf(alsoInView) : nullptr) {
    both = render::unionFrame(*frame, *other);
    frame = &*both;
  }
  render::ViewRequest request;
  request.view = name;
  request.margin = framingMargin();
  request.width = std::max(1, width);
  request.height = std::max(1, height);
  auto settings = render::settingsFor(presetOf(label, bare_), *frame, request);
  if (!settings) return tl::unexpected(settings.error());
  camera_ = settings->camera;
  framedCamera_ = camera_;
  framedPixels_ = {request.width, request.height};
  viewName_ = name;
  changed();
  return {};
}

// A structure's extent times this fills the view: room around it to orbit and hover; the whole
// grid as the render command frames it.
double ExploreState::framingMargin() const { return wholeVolume_ ? 1.6 : 2.5; }

bool ExploreState::bringIntoView(std::uint16_t label, int width, int height) {
  const render::StructureFrame* frame = frameOf(label);
  width = std::max(1, width);
  height = std::max(1, height);
  if (!frame) return false;
  const render::Camera framed = render::frameCamera(*frame, camera_, double(width) / double(height), framingMargin());
  if (render::shareInView(*frame, camera_, width, height) >= kShownWhole && camera_.distanceMm <= kFarthestShown * framed.distanceMm)
    return false;
  camera_ = framed;
  framedCamera_ = camera_;
  framedPixels_ = {width, height};
  changed();
  return true;
}

void ExploreState::setCamera(const render::Camera& camera) {
  camera_ = camera;
  framedCamera_ = camera;
  changed();
}

void ExploreState::orbit(double azimuthDeg, double elevationDeg) {
  camera_.orbit(azimuthDeg, elevationDeg);
  changed();
}

void ExploreState::zoom(double factor) {
  camera_.zoom(factor);
  changed();
}

void ExploreState::pan(double dxPixels, double dyPixels, int viewHeightPixels) {
  const double mmPerPixel = 2 * camera_.distanceMm * std::tan(camera_.fovYDeg * M_PI / 360) / std::max(1, viewHeightPixels);
  const Vec3 right = cross(camera_.forward(), camera_.up());
  camera_.target = camera_.target - (dxPixels * mmPerPixel) * right + (dyPixels * mmPerPixel) * camera_.up();
  changed();
}

bool ExploreState::setClip(const ClipSettings& clip) {
  ClipSettings c = clip;
  c.axis = std::clamp(c.axis, 0, 2);
  if (c == clip_) return false;
  clip_ = c;
  changed();
  return true;
}

bool ExploreState::usePreset(std::uint16_t label, const render::Preset& preset, float t) {
  const bool bare = preset.mode == render::RenderMode::Bare;
  auto it = presets_.find({label, bare});
  if (bare == bare_ && t == t_ && it != presets_.end() && it->second == preset) return false;
  bare_ = bare;
  t_ = t;
  presets_[{label, bare}] = preset;
  changed();
  return true;
}

void ExploreState::setFieldShown(std::uint16_t label, const std::string& key) {
  if (label == fieldLabel_ && key == fieldKey_) return;
  fieldLabel_ = label;
  fieldKey_ = key;
  ++revision_;
}

void ExploreState::setPresetOverride(const std::optional<render::Preset>& preset, std::uint64_t editRevision) {
  if (!preset && !override_) return;
  if (preset && override_ && editRevision == overrideRevision_) return;
  override_ = preset;
  overrideRevision_ = editRevision;
  if (preset) {  // mode and t follow the edited preset
    bare_ = preset->mode == render::RenderMode::Bare;
    t_ = preset->t;
  }
  changed();
}

}  // namespace at::app
