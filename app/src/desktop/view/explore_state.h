// What the explore view shows, without SDL, GL or ImGui: the dataset's structures grouped by
// system, the selected and hovered structure, WDT or bare preset, the blend t, the camera and its
// named view, the clipping plane, the presets in use (the shipped ones, a lesson or study step's,
// or the expert's edited copy) and the distance field on screen.
//
// shown() is the one place that decides what the image shows. revision() changes exactly when
// that image would change (the renderer re-renders then); activity() changes on every user action
// (a hover over the same structure included), which keeps the view "moving" for the scheduler.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"
#include "render/camera.h"
#include "render/derived_preset.h"
#include "render/preset.h"
#include "render/scene.h"
#include "volume/structure.h"
#include "wdt/wdt.h"

namespace at::app {

// The clipping plane as the explore panel offers it: one of the three patient axes through the
// camera's target, shifted by an offset, either side cut away.
struct ClipSettings {
  bool on = false;
  int axis = 0;  // 0: left–right (x), 1: anterior–posterior (y), 2: inferior–superior (z)
  bool flip = false;
  float offsetMm = 0;
  bool operator==(const ClipSettings&) const = default;
};

class ExploreState {
 public:
  using MessageSink = std::function<void(const std::string&)>;
  // `library`: the shipped presets (outlives the state). `messages`: presets that fail to load.
  ExploreState(const render::PresetLibrary& library, MessageSink messages);

  // Shows `dataset` (kept by the caller, alive while shown), starting on `startStructure` (or its
  // first structure with voxels) with the step preset `startPreset` ("" = its WDT preset). A
  // dataset with no structure that has voxels (an unlabelled scan) is shown whole: see wholeVolume().
  Status setDataset(const Dataset& dataset, const std::string& startStructure, const std::string& startPreset);
  const Dataset& dataset() const { return *dataset_; }
  // The shown dataset's labels or structures were edited in place (the segment editor): the
  // frames of the `edited` labels are measured again and the browser is rebuilt from its
  // structures. An unlabelled dataset whose first structure gets voxels leaves whole-volume mode
  // for the structures' WDT view (and returns to it when the last one loses them). `current` (the
  // editor's structure) is selected when it is among the edited labels and has voxels; a
  // selected or hovered structure left without voxels is let go. The camera stays. `editBox`: the
  // box holding every voxel that changed (as StructureFrame::voxelBox); none when only names,
  // colours or the list of structures changed.
  void labelsEdited(const std::vector<std::uint16_t>& edited, std::uint16_t current,
                    const std::optional<std::array<int, 6>>& editBox);
  bool hasStructure(std::uint16_t label) const { return frames_.count(label) > 0; }
  // The frame of a structure with voxels; in whole-volume mode label 0's is the grid's.
  const render::StructureFrame* frameOf(std::uint16_t label) const;
  // The dataset has no structure with voxels: the whole volume is drawn with a data TF derived
  // from its intensities (render/volume_preset.h: WDT mode at t = 1 over a neutral field, so no
  // distance field is ever computed), framed around the grid; nothing is selected or hovered.
  bool wholeVolume() const { return wholeVolume_; }
  // Structures with voxels by system, in the dataset's order (the browser's tree).
  const std::vector<std::pair<std::string, std::vector<const Structure*>>>& bySystem() const { return bySystem_; }

  // What the image shows: the one place that decides it.
  struct Shown {
    std::uint16_t label = 0;  // highlighted: the structure whose field is on screen in field modes
    render::Preset preset;    // t applied; mode Bare when bare or no field is on screen yet
  };
  Shown shown() const;
  std::uint16_t selected() const { return selected_; }
  std::uint16_t hovered() const { return hovered_; }
  std::uint16_t shownLabel() const { return hovered_ ? hovered_ : selected_; }  // hovered, else selected
  bool bare() const { return bare_; }
  float t() const { return t_; }
  const render::Camera& camera() const { return camera_; }
  const std::string& viewName() const { return viewName_; }
  // The view the structure was last framed in (setView, or a step's camera through setCamera) and
  // that view's pixel size; orbiting and zooming leave it: the field's distance unit is measured
  // in it (render/field_scale.h), so the image does not change scale while the user turns it.
  const render::Camera& framedCamera() const { return framedCamera_; }
  std::array<int, 2> framedPixels() const { return framedPixels_; }
  const ClipSettings& clip() const { return clip_; }
  std::optional<render::ClipPlane> clipPlane() const;

  // The dataset's intensity levels, which derived presets are made from.
  const render::IntensityLevels& levels() const { return levels_; }
  // The preset of a structure in a mode: a step's preset when one was set, else the shipped one,
  // else one derived from the dataset's levels (else a built-in default, with a message).
  const render::Preset& presetOf(std::uint16_t label, bool bare) const;
  // The preset of a structure in any mode, as `render --mode` finds it: presetOf's when that is in
  // `mode` already (a step's preset included), else the shipped one, else one derived from the
  // dataset's levels. The whole volume keeps its one preset, in `mode`.
  render::Preset presetInMode(std::uint16_t label, render::RenderMode mode) const;
  // The WDT parameters of the field `label` needs (the expert's edited preset while editing).
  std::optional<WdtParams> fieldParams(std::uint16_t label) const;
  // The preset picking classifies with: the WDT view's, whatever the mode (the user points at the
  // anatomy under the cursor even when bare mode shows one structure).
  const render::Preset& pickPreset() const;
  // The structure whose field is on screen (0 = none) and its key.
  std::uint16_t fieldLabel() const { return fieldLabel_; }

  // Changes. Each returns whether anything changed; revision() moves when the image would.
  bool select(std::uint16_t label);  // the camera stays (bringIntoView moves it)
  bool setHovered(std::uint16_t label);
  bool setBare(bool bare);
  bool setT(float t);
  // The named view framing the shown structure with room around it to orbit and hover, for an
  // image of width × height pixels; an unknown name is an error and the camera stays. A non-zero
  // `alsoInView` (a structure of the dataset) is framed with it, unmarked: a locate question's
  // target beside the region it is asked in.
  Status setView(const std::string& name, int width, int height, std::uint16_t alsoInView = 0);
  // A step's free camera replaces the view's framing (the named view stays the view's name).
  void setCamera(const render::Camera& camera);
  // Where under kShownWhole of the structure's points lie inside a width × height image, or the
  // camera is more than kFarthestShown times as far as framing it would put it (it shows at under
  // half the size), frames it from the side the camera looks from now (its direction and up kept,
  // the margin setView uses): a structure chosen from the list may lie outside the view that framed
  // the previous one (the abdomen's spleen framed, the liver chosen: most of it off screen), or be a
  // speck in it (the right kidney chosen after the liver: 87 of 720 pixels high). Returns whether
  // the camera moved; a structure the view shows whole and large enough keeps the camera, zoom and
  // orbit included.
  bool bringIntoView(std::uint16_t label, int width, int height);
  static constexpr double kShownWhole = 0.98;
  static constexpr double kFarthestShown = 2.0;
  void orbit(double azimuthDeg, double elevationDeg);
  void zoom(double factor);
  void pan(double dxPixels, double dyPixels, int viewHeightPixels);
  bool setClip(const ClipSettings& clip);
  // A lesson or study step: the structure's preset in that mode, the mode and the blend t.
  bool usePreset(std::uint16_t label, const render::Preset& preset, float t);
  // The field of `label` with `key` is on screen now (label 0: none).
  void setFieldShown(std::uint16_t label, const std::string& key);
  // The expert's edited preset replaces the view's while set (mode and t follow it); call again
  // with the same preset after each edit (`editRevision` tells edits apart).
  void setPresetOverride(const std::optional<render::Preset>& preset, std::uint64_t editRevision);
  bool presetOverridden() const { return override_.has_value(); }
  // Something outside the state changed the image (the viewport's size).
  void touch() { ++revision_; }
  // The user did something that does not change the image (hovering the same structure).
  void noteActivity() { ++activity_; }

  std::uint64_t revision() const { return revision_; }
  std::uint64_t activity() const { return activity_; }

 private:
  double framingMargin() const;
  std::uint16_t displayLabel() const;
  void rebuildBrowser();  // bySystem_ from the dataset's structures with frames
  void startOn(const Structure& structure, const std::string& presetId);  // selected, with its step preset
  void changed() {  // the image changes, and the user (or a script) caused it
    ++revision_;
    ++activity_;
  }
  template <class F>
  bool changeShown(F&& change);  // runs `change`; bumps the revision when the shown label moves

  const render::PresetLibrary& library_;
  MessageSink messages_;
  const Dataset* dataset_ = nullptr;
  render::IntensityLevels levels_;  // of dataset_'s volume
  std::vector<std::pair<std::string, std::vector<const Structure*>>> bySystem_;
  std::map<std::uint16_t, render::StructureFrame> frames_;
  bool wholeVolume_ = false;
  render::StructureFrame volumeFrame_;  // the grid's (whole-volume mode)
  mutable std::map<std::pair<std::uint16_t, bool>, render::Preset> presets_;
  std::optional<render::Preset> override_;
  std::uint64_t overrideRevision_ = 0;

  std::uint16_t selected_ = 0, hovered_ = 0;
  bool bare_ = false;
  float t_ = 0.5f;
  render::Camera camera_;
  render::Camera framedCamera_;
  std::array<int, 2> framedPixels_{512, 512};
  std::string viewName_;
  ClipSettings clip_;
  std::uint16_t fieldLabel_ = 0;
  std::string fieldKey_;
  std::uint64_t revision_ = 1, activity_ = 1;
};

}  // namespace at::app
