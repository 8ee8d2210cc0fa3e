#include "expert/tf_editor.h"

#include <algorithm>

#include "core/strings.h"
#include "db/connection.h"
#include "db/preset_store.h"

namespace at::app {

using json = nlohmann::json;

TfEditor::TfEditor(const Dataset& dataset, db::Database& database, EventSink events)
    : database_(database), events_(std::move(events)) {
  const auto& v = dataset.volume.voxels;
  if (!v.empty()) {
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    huMin_ = double(*lo);
    huMax_ = std::max(double(*hi) + 1, huMin_ + 1);
  }
  histogram_ = render::logHistogram(v, 128, huMin_, huMax_);
}

void TfEditor::start(const render::Preset& base, const std::string& structure, ModePresets modePresets) {
  preset_ = base;
  structure_ = structure;
  modePresets_ = std::move(modePresets);
  otherModes_.clear();
  active_ = true;
  edited();
  events_({{"event", "expert"}, {"structure", structure}, {"preset", json::parse(render::presetToJson(preset_))}});
}

namespace {
const render::TfAxisRange& rangeOf(bool data) {
  static const render::TfAxisRange dataRange = render::dataAxisRange(), distanceRange = render::distanceAxisRange();
  return data ? dataRange : distanceRange;
}
const char* nameOf(bool data) { return data ? "data" : "distance"; }
}  // namespace

Result<std::size_t> TfEditor::addPoint(bool data, double x, std::optional<render::Rgba> rgba) {
  auto& pts = points(data);
  const render::Rgba c = rgba ? *rgba : render::TransferFunction1D::fromPoints(pts)->evaluate(x);
  auto i = render::addTfPoint(pts, x, c, rangeOf(data));
  if (!i) return i;
  edited();
  events_({{"event", "tf_point"}, {"tf", nameOf(data)}, {"index", *i}, {"x", pts[*i].x}});
  return i;
}

Status TfEditor::movePoint(bool data, std::size_t index, double x, float alpha) {
  auto& pts = points(data);
  if (index >= pts.size()) return fail("no point " + std::to_string(index));
  auto moved = render::moveTfPoint(pts, index, x, alpha, rangeOf(data));
  if (!moved) return tl::unexpected(moved.error());
  edited();
  events_({{"event", "tf_point"}, {"tf", nameOf(data)}, {"index", index}, {"x", *moved}});
  return {};
}

Status TfEditor::deletePoint(bool data, std::size_t index) {
  auto st = render::deleteTfPoint(points(data), index);
  if (st) edited();
  return st;
}

Status TfEditor::setColour(bool data, std::size_t index, const render::Rgba& rgba) {
  auto& pts = points(data);
  if (index >= pts.size()) return fail("no point " + std::to_string(index));
  auto st = render::setTfPointColour(pts, index, rgba);
  if (st) edited();
  return st;
}

void TfEditor::switchMode(render::RenderMode mode) {
  if (mode == preset_.mode) return;
  otherModes_[preset_.mode] = preset_;
  auto kept = otherModes_.find(mode);
  if (kept != otherModes_.end()) {
    preset_ = kept->second;
    otherModes_.erase(kept);
  } else if (modePresets_) {
    preset_ = modePresets_(mode);
    preset_.mode = mode;
  } else {
    preset_.mode = mode;
  }
  edited();
  events_({{"event", "expert_mode"}, {"mode", render::toString(mode)}, {"preset", json::parse(render::presetToJson(preset_))}});
}

Status TfEditor::setParameters(const render::Preset& p) {
  auto valid = render::parsePreset(render::presetToJson(p), "preset_set");
  if (!valid) return tl::unexpected(valid.error());
  preset_ = p;
  edited();
  return {};
}

Status TfEditor::saveAs(const std::string& name, const std::optional<std::string>& exportPath) {
  const std::string id = str::identifier(name);
  if (id.empty()) return fail("save preset: the name '" + name + "' has no letters or digits");
  render::Preset p = preset_;
  p.name = name;
  p.id = id;
  if (!structure_.empty()) p.structure = structure_;
  const std::string text = render::presetToJson(p);
  auto valid = render::parsePreset(text, id);
  if (!valid) return tl::unexpected(withContext("save preset", valid.error()));
  const db::StoredPreset stored{id, p.structure, render::toString(p.mode), text};
  if (auto st = db::savePreset(database_, stored); !st) return st;
  json ev = {{"event", "preset_saved"}, {"id", id}, {"db", db::pathOf(database_)}};
  if (exportPath) {
    if (auto st = render::savePreset(p, *exportPath); !st) return st;
    ev["export"] = *exportPath;
  }
  events_(ev);
  return {};
}

}  // namespace at::app
