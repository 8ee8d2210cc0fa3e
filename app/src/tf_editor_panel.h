// The expert level of the desktop app (issue 7): spline editors for the data TF (over a log-scaled
// HU histogram of the dataset) and the distance TF (over 0..1), sliders for the preset's other
// parameters, and "Save as" a named preset into the database and, optionally, a JSON file.
//
// The panel edits a copy of a preset; the app shows that copy (live preview) while the panel is
// active and asks the field worker for fields with its weights. revision() changes on every edit.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "render/preset.h"
#include "render/tf_edit.h"
#include "core/error.h"
#include "volume/structure.h"

namespace at::db {
class Database;
}

namespace at::app {

class TfEditorPanel {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  // `database`: where "Save as" stores presets (the app's one connection; it outlives the panel).
  TfEditorPanel(const Dataset& dataset, db::Database& database, EventSink events);

  bool active() const { return active_; }
  void stop() { active_ = false; }
  // Starts editing a copy of `base`, made for `structure` (its id; empty for none).
  void start(const render::Preset& base, const std::string& structure);
  const render::Preset& preset() const { return preset_; }
  std::uint64_t revision() const { return revision_; }

  // Draws the editor as a window at the window's right edge; true when the preset changed.
  bool draw(float x, float width, float height);

  // Scripted actions (the "do" names are handled()). Errors name the action and the problem.
  static bool handled(const std::string& what);
  Status scriptAction(const std::string& what, const nlohmann::json& a);

  // Validates (parsePreset of its JSON), stores under an id made from `name`, and exports the JSON
  // to `exportPath` when given.
  Status saveAs(const std::string& name, const std::optional<std::string>& exportPath);

 private:
  struct Selection {
    bool data = true;
    std::size_t index = 0;
  };
  bool splineEditor(const char* id, bool data, float width, float height);
  std::vector<render::TfPoint>& points(bool data) { return data ? preset_.dataTf : preset_.distanceTf; }
  Result<bool> tfArg(const nlohmann::json& a) const;  // "tf": "data" | "distance"
  void changed() { ++revision_; }

  db::Database& database_;
  EventSink events_;
  render::Preset preset_;
  std::string structure_;
  bool active_ = false;
  std::uint64_t revision_ = 0;
  double huMin_ = -1024, huMax_ = 3071;  // the data axis shown: the dataset's HU range
  std::vector<float> histogram_;         // log-scaled, over [huMin_, huMax_]
  std::optional<Selection> dragging_, menuFor_;
  char saveName_[64] = "my_preset";
  char exportPath_[256] = "";
  std::string saveStatus_;
};

}  // namespace at::app
