// The expert level without drawing (the Expert panel draws its spline editors and sliders; the UI
// script drives the same commands): a copy of a preset being edited — points of the data TF (over
// the dataset's HU range, with a log-scaled histogram) and of the distance TF (over 0..1), mode,
// t, α, lighting and weights — and "Save as" a named preset into the database and, optionally, a
// JSON file. The explore view shows the copy while editing (live preview) and asks the field
// service for fields with its weights; revision() changes on every edit.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "render/preset.h"
#include "render/tf_edit.h"
#include "volume/structure.h"

namespace at::db {
class Database;
}

namespace at::app {

class TfEditor {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  // The structure's preset in a mode (the one `render --mode` uses), which a mode not yet edited
  // starts from.
  using ModePresets = std::function<render::Preset(render::RenderMode)>;
  // `database`: where "Save as" stores presets (the app's one connection; it outlives the editor).
  TfEditor(const Dataset& dataset, db::Database& database, EventSink events);

  bool active() const { return active_; }
  // Starts editing a copy of `base`, made for `structure` (its id; empty for none) [expert];
  // `modePresets` gives the structure's preset in the other modes.
  void start(const render::Preset& base, const std::string& structure, ModePresets modePresets);
  void stop() { active_ = false; }
  const render::Preset& preset() const { return preset_; }
  std::uint64_t revision() const { return revision_; }

  // Point edits on the data TF (`data`) or the distance TF; errors name the problem.
  Result<std::size_t> addPoint(bool data, double x, std::optional<render::Rgba> rgba);  // [tf_point]
  Status movePoint(bool data, std::size_t index, double x, float alpha);              // [tf_point]
  Status deletePoint(bool data, std::size_t index);
  Status setColour(bool data, std::size_t index, const render::Rgba& rgba);
  // Shows the preset in `mode`: the copy edited in that mode since start() when there is one (no
  // edit is lost by switching away and back), else the structure's preset in that mode — each mode
  // has its own transfer functions, t and lighting, so the WDT's would not read as fuzzy or
  // lighting [expert_mode].
  void switchMode(render::RenderMode mode);
  // The other parameters at once (t, α, lighting, weights; the mode too, keeping everything
  // else); refused unless the preset still validates.
  Status setParameters(const render::Preset& withParameters);
  // The panel's widgets edit the copy in place, then say so.
  render::Preset& editable() { return preset_; }
  void edited() { ++revision_; }

  // Validates (parsePreset of its JSON), stores under an id made from `name`, and exports the JSON
  // to `exportPath` when given [preset_saved].
  Status saveAs(const std::string& name, const std::optional<std::string>& exportPath);

  // The data axis shown: the dataset's HU range and its log-scaled histogram.
  double huMin() const { return huMin_; }
  double huMax() const { return huMax_; }
  const std::vector<float>& histogram() const { return histogram_; }

 private:
  std::vector<render::TfPoint>& points(bool data) { return data ? preset_.dataTf : preset_.distanceTf; }
  db::Database& database_;
  EventSink events_;
  render::Preset preset_;
  std::string structure_;
  ModePresets modePresets_;
  std::map<render::RenderMode, render::Preset> otherModes_;  // edited copies of the modes not shown
  bool active_ = false;
  std::uint64_t revision_ = 0;
  double huMin_ = -1024, huMax_ = 3071;
  std::vector<float> histogram_;
};

}  // namespace at::app
