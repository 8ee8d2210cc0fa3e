#include "view/field_unit.h"

#include <chrono>
#include <exception>
#include <utility>

#include "render/picture_scale.h"

namespace at::app {

bool FieldUnitKey::operator==(const FieldUnitKey& o) const {
  const bool byView = seen || render::unitFromNeighbourBone(mode) || render::judgedOnPicture(mode);
  return field == o.field && label == o.label && bone == o.bone && mode == o.mode && seen == o.seen &&
         (!byView || view == o.view) && (!render::judgedOnPicture(mode) || picturePreset == o.picturePreset);
}

render::FieldScale measureFieldUnit(const FieldUnitRequest& request) {
  const FieldUnitKey& k = request.key;
  const FloatVolume& field = request.field->distances;
  render::FieldScale scale =
      render::fieldScale(field, *request.volume, nullptr, request.frame, k.bone, k.seen ? &k.view : nullptr);
  if (render::unitFromNeighbourBone(k.mode))
    render::unitFromNeighbours(scale, render::neighbourBone(field, *request.volume, nullptr, k.bone, k.view), k.mode);
  const LabelMap* labels = request.labelsCopy ? request.labelsCopy.get() : request.labels;
  if (render::judgedOnPicture(k.mode) && labels && !labels->empty()) {
    render::SceneVolumes scene;
    scene.volume = request.volume;
    scene.labels = labels;
    scene.field = &field;
    scene.selected = k.label;
    scene.gradients = request.gradients;
    render::RenderSettings settings;
    settings.preset = k.picturePreset;
    settings.camera = k.view.camera;
    settings.width = k.view.width;
    settings.height = k.view.height;
    settings.clip = k.view.clip;
    render::scaleFromPicture(scale, scene, settings);
  }
  return scale;
}

FieldUnits::FieldUnits(FieldUnitMeasure measure, bool synchronous)
    : measure_(measure ? std::move(measure) : FieldUnitMeasure(measureFieldUnit)), synchronous_(synchronous) {}

FieldUnits::~FieldUnits() { reset(); }

void FieldUnits::reset() {
  if (running_ && running_->result.valid()) running_->result.wait();
  running_.reset();
  queued_.reset();
  taken_.clear();
  wanted_.reset();
}

const FieldUnits::Taken* FieldUnits::takenFor(const FieldUnitKey& key) const {
  for (const Taken& t : taken_)
    if (t.key == key && !t.field.expired()) return &t;
  return nullptr;
}

const FieldUnits::Taken* FieldUnits::takenForLabel(std::uint16_t label) const {
  for (const Taken& t : taken_)
    if (t.key.label == label) return &t;
  return nullptr;
}

void FieldUnits::take(const FieldUnitKey& key, const std::shared_ptr<const DistanceField>& field,
                      const render::FieldScale& scale) {
  std::erase_if(taken_, [&](const Taken& t) { return t.key == key || t.field.expired(); });
  taken_.insert(taken_.begin(), Taken{key, field, scale});
  if (taken_.size() > kKeptUnits) taken_.resize(kKeptUnits);
}

void FieldUnits::start(const FieldUnitRequest& request) {
  FieldUnitMeasure measure = measure_;
  FieldUnitRequest copied = request;
  if (copied.labels && render::judgedOnPicture(copied.key.mode)) copied.labelsCopy = std::make_shared<const LabelMap>(*copied.labels);
  copied.labels = nullptr;  // the worker reads the copy only
  running_ = Running{request.key, request.field, request.frame,
                     std::async(std::launch::async, [measure, copied = std::move(copied)] { return measure(copied); })};
}

std::optional<render::FieldScale> FieldUnits::unitFor(const FieldUnitRequest& request) {
  const FieldUnitKey& key = request.key;
  wanted_ = key;
  if (const Taken* t = takenFor(key)) {
    queued_.reset();  // nothing newer is wanted
    return t->scale;
  }
  if (synchronous_) {
    const render::FieldScale scale = measure_(request);
    take(key, request.field, scale);
    return scale;
  }
  if (running_ && running_->key == key) queued_.reset();  // back to the running one's key
  else if (running_) queued_ = request;                    // the running one is superseded
  else start(request);
  if (const Taken* t = takenForLabel(key.label)) return t->scale;
  return std::nullopt;
}

bool FieldUnits::poll() {
  if (!running_ || running_->result.wait_for(std::chrono::seconds(0)) != std::future_status::ready) return false;
  Running done = std::move(*running_);
  running_.reset();
  render::FieldScale scale;
  try {
    scale = done.result.get();
  } catch (const std::exception&) {
    // Not measured (out of memory): the size-based unit, so that the key is not tried every frame.
    scale = render::FieldScale{};
    scale.distanceUnit = render::distanceUnitFor(done.frame);
  }
  const bool wanted = wanted_ && done.key == *wanted_;
  if (wanted) take(done.key, done.field, scale);
  if (queued_) {
    const FieldUnitRequest next = std::move(*queued_);
    queued_.reset();
    start(next);
  }
  return wanted;
}

}  // namespace at::app
