// The distance unit of the field on screen (render::fieldScale), measured off the UI thread.
//
// Why: the measure casts up to 128 × 128 rays through the framed view and walks the field around
// the structure — 115–305 ms per field on the skull CT (bench/RESULTS.md, NVIDIA H200 host)
// against a hover cycle of 6–11 ms. Measured on the UI thread, every newly hovered structure
// stalled the desktop. Here it runs on a worker: until the unit is there, the view keeps the last
// unit taken for the same structure (a finer field of it, another view), else the caller's
// size-based unit; once it is there, poll() takes it on the UI thread and says so, and the view
// renders again.
//
// Contract: at most one measure runs. A request for another key while one runs is queued (a newer
// one replaces it) and started when the running one ends; the result of a measure whose key is no
// longer the wanted one is dropped, never taken. Synchronous mode (scripted runs: each screenshot
// shows its field's own unit) measures on the calling thread inside unitFor. The field a measure
// reads is kept alive by its request; the volume must outlive it: reset() (and the destructor)
// wait for a running measure.
#pragma once

#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <vector>

#include "render/field_scale.h"
#include "render/gradient_volume.h"
#include "render/scene.h"
#include "volume/grid.h"
#include "wdt/wdt.h"

namespace at::app {

// What a unit is measured for: the field (by identity), its structure, the bone levels of the
// preset's data TF, its mode, whether the view's seen bone counts (render::unitFromSeenBone) and
// the framed view — compared only where the mode's unit depends on it (seen,
// render::unitFromNeighbourBone or render::judgedOnPicture) — and in the modes judged on the
// picture (fuzzy, lighting, outline) the preset the picture is drawn with
// (render/picture_scale.h; its t set to 0 by the caller: the picture is judged at its own t, so
// moving the slider measures nothing).
struct FieldUnitKey {
  const DistanceField* field = nullptr;
  std::uint16_t label = 0;
  render::BoneLevels bone;
  render::RenderMode mode = render::RenderMode::Wdt;
  bool seen = false;
  render::FieldView view;
  render::Preset picturePreset;
  bool operator==(const FieldUnitKey& o) const;
};

struct FieldUnitRequest {
  FieldUnitKey key;
  std::shared_ptr<const DistanceField> field;  // key.field, kept alive while it is measured
  const Volume* volume = nullptr;              // the scan the field was computed on
  render::StructureFrame frame;                // the structure's frame (key.label)
  // Fuzzy and lighting: the shown label map (owned by the UI thread, which edits it: start() hands the worker a
  // copy, `labelsCopy`) and the volume's gradients (they must outlive the measure, as the volume).
  const LabelMap* labels = nullptr;
  const render::GradientVolume* gradients = nullptr;
  std::shared_ptr<const LabelMap> labelsCopy;
};

// How a request is measured: as render::applyFieldScale measures it for the render command
// (fieldScale, then unitFromNeighbours for fuzzy and lighting, then with the labels
// scaleFromPicture) in measureFieldUnit, unless a test
// puts a stand-in in its place. Called on the worker thread (synchronous mode: the caller's).
using FieldUnitMeasure = std::function<render::FieldScale(const FieldUnitRequest&)>;
render::FieldScale measureFieldUnit(const FieldUnitRequest& request);

class FieldUnits {
 public:
  // `measure` empty: measureFieldUnit.
  explicit FieldUnits(FieldUnitMeasure measure = {}, bool synchronous = false);
  ~FieldUnits();
  FieldUnits(const FieldUnits&) = delete;
  FieldUnits& operator=(const FieldUnits&) = delete;

  // The unit for `request` (it becomes the wanted key): the measured one once taken (the last
  // kKeptUnits keys taken are kept while their fields live: hovering back to a structure whose
  // field is still cached measures nothing); until then the last unit taken for the same label,
  // else nullopt (the caller's size-based unit). Starts (or queues) its measure when it is
  // neither taken nor running. Never waits for a running measure.
  static constexpr std::size_t kKeptUnits = 8;
  std::optional<render::FieldScale> unitFor(const FieldUnitRequest& request);
  // UI thread, once a frame: takes a finished measure and starts the queued one. True when the
  // unit of the wanted key was taken (the image must be rendered again).
  bool poll();
  // A measure runs or is queued (the image may still change without input).
  bool measuring() const { return running_.has_value() || queued_.has_value(); }
  // Waits for a running measure and forgets everything (the volume it reads goes away).
  void reset();

 private:
  void start(const FieldUnitRequest& request);

  FieldUnitMeasure measure_;
  bool synchronous_ = false;
  std::optional<FieldUnitKey> wanted_;
  struct Taken {
    FieldUnitKey key;
    // While it lives, no other field can have key.field's address; expired, the key matches
    // nothing (its unit still stands in for its label).
    std::weak_ptr<const DistanceField> field;
    render::FieldScale scale;
  };
  std::vector<Taken> taken_;  // the most recent first, at most kKeptUnits
  const Taken* takenFor(const FieldUnitKey& key) const;
  const Taken* takenForLabel(std::uint16_t label) const;
  void take(const FieldUnitKey& key, const std::shared_ptr<const DistanceField>& field, const render::FieldScale& scale);
  struct Running {
    FieldUnitKey key;
    std::shared_ptr<const DistanceField> field;
    render::StructureFrame frame;
    std::future<render::FieldScale> result;
  };
  std::optional<Running> running_;
  std::optional<FieldUnitRequest> queued_;
};

}  // namespace at::app
