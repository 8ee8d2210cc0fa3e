// The segment editor's UI-script actions: each calls the SegmentController command the Segment
// window's widgets call.
#include <algorithm>
#include <iterator>

#include <nlohmann/json.hpp>

#include "script/script_interpreter.h"
#include "segment_editor/segment_controller.h"

namespace at::app {

using nlohmann::json;

ScriptInterpreter::Feature ScriptInterpreter::segmentActions() {
  using S = ScriptInterpreter;
  const ScriptArgument voxel{"voxel", "[i, j, k]"};
  const ScriptArgument brush{"brush_mm?", "the brush's diameter"};
  return {"segment",
          "the segment editor and the Slices window",
          {
              {"segment_open", {{"open?", "true (default) opens, false closes"}},
               "Shows the Segment window on the dataset on screen, with the Slices window.", &S::segmentOpen},
              {"segment_label",
               {{"name", "a label name (added when new; background is label 0)"},
                {"grow_range?", "\"bone\", [low, high] or \"none\": the label grows only in that range"}},
               "Paints that label next; reports segment_label {name, label}.", &S::segmentLabel},
              {"segment_seeds", {{"save?", "a seeds file to write"}, {"load?", "a seeds file to read"}},
               "Saves the painted seeds (with the growth settings and label ranges) or loads a file's.", &S::segmentSeeds},
              {"segment_slice", {{"axis", "x, y, z or 0, 1, 2: the voxel axis it crosses"}, {"index", "the slice"}}, "Shows that slice, in patient orientation (radiological).", &S::segmentSlice},
              {"segment_seed",
               {voxel, brush, {"low?", "with high: seed only values in low … high joined to the voxel"},
                {"high?", "with low (a local threshold; any label, the background too)"}},
               "Seeds of the current label in the brush around the voxel.", &S::segmentSeed},
              {"segment_grow", {{"wait?", "true (default): done once the growth is applied"}},
               "Grows the labels from their seeds; reports segment_grown.", &S::segmentGrow},
              {"segment_undo", {}, "Undoes the last edit (Ctrl+Z).", &S::segmentUndo},
              {"segment_redo", {}, "Redoes it (Ctrl+Shift+Z).", &S::segmentRedo},
              {"segment_review", {{"name", "a label name"}, {"state", "not_started, in_progress, completed or flagged"}},
               "Sets a structure's review state.", &S::segmentReview},
              {"segment_tool", {{"tool", "seeds, threshold, paint or erase"}, brush},
               "Chooses what a click does (paint and erase: also in the 3-D view).", &S::segmentTool},
              {"segment_clear_seeds", {}, "Clears the seeds.", &S::segmentClearSeeds},
              {"segment_save", {{"out?", "export to .nii, .nii.gz or .seg.nrrd instead"}, {"names?", "the names file to write"}},
               "Stores the labels into the dataset store (an imported dataset), or exports them.", &S::segmentSave},
              {"segment_threshold",
               {voxel, {"low?", "default: the dataset's window"}, {"high?", "default: the dataset's window"},
                {"min_diameter_mm?", "default 0"}},
               "The connected region of values in range under the voxel takes the current label.", &S::segmentThreshold},
              {"segment_margin", {{"mm", "grow by (negative: shrink)"}}, "Grows or shrinks the current structure.",
               &S::segmentMargin},
              {"segment_hollow", {{"mm", "the wall's thickness"}}, "Hollows the current structure.", &S::segmentHollow},
              {"segment_split", {{"min_diameter_mm?", "cut bridges thinner than this (default 0)"}, {"min_voxels?", "the smallest piece made a structure (default 1)"}},
               "The current structure's disconnected pieces become structures NAME (2), … by size.", &S::segmentSplit},
              {"segment_growth",
               {{"bone_only?", "true: grow only into the data's bone range (the \"bone\" button)"},
                {"range?", "[low, high]: grow only into these values"}, {"limit?", "false: no range limit"},
                {"base_per_voxel?", "the travel cost per voxel"}, {"window?", "[low, high]: the values mapped to 0 … 1"},
                {"smoothing?", "edge-preserving smoothing, sigma in voxels"}, {"defaults?", "true: the data's defaults first"},
                {"wait?", "true (default): done once a growth on screen is grown again"}},
               "Sets the growth settings; reports segment_growth_settings.", &S::segmentGrowth},
              {"segment_system", {{"name", "a label name"}, {"system", "its browsing group (empty: none)"}},
               "Sets a structure's system, stored with segment_save.", &S::segmentSystem},
              {"slices_open",
               {{"open?", "true (default) or false"}, {"crosshair?", "[i, j, k]: through that voxel"},
                {"label_alpha?", "the labels' opacity"}},
               "Shows the Slices window.", &S::slicesOpen},
          }};
}

// {"do": "segment_open"}: shows the Segment window (the editor of the dataset on screen) with the
// Slices window, as the explore panel's Segment... button does ({"open": false} closes the editor).
ScriptInterpreter::Outcome ScriptInterpreter::segmentOpen(Context& c) {
  const bool open = c.action.value("open", true);
  c.model.segmenter().windowOpen = open;
  if (open) c.model.slices().windowOpen = true;
  return Progress::Done;
}

// {"do": "segment_label", "name": "liver"}: paints that label next, adding it when the editor has
// no label of that name ("background" is label 0).
ScriptInterpreter::Outcome ScriptInterpreter::segmentLabel(Context& c) {
  SegmentController& s = c.model.segmenter();
  const std::string name = c.action.at("name").get<std::string>();
  if (auto existing = s.labelNamed(name)) {
    if (auto st = s.setCurrentLabel(*existing); !st) return tl::unexpected(st.error());
  } else if (auto added = s.addLabel(name); !added) {
    return tl::unexpected(added.error());
  }
  if (c.action.contains("grow_range")) {
    const json& range = c.action.at("grow_range");
    std::optional<SegmentController::LabelGrowRange> wanted;
    if (range == "bone") {
      wanted = SegmentController::LabelGrowRange{std::nullopt, true};
    } else if (range.is_array() && range.size() == 2 && range[0].is_number() && range[1].is_number()) {
      wanted = SegmentController::LabelGrowRange{std::array<double, 2>{range[0].get<double>(), range[1].get<double>()}, false};
    } else if (range != "none") {
      return fail("ui script: segment_label: \"grow_range\" must be \"bone\", [low, high] or \"none\", not " + range.dump());
    }
    if (auto st = s.setLabelGrowRange(s.currentLabel(), wanted); !st) return tl::unexpected(st.error());
  }
  c.model.event({{"event", "segment_label"}, {"name", name}, {"label", s.currentLabel()}});
  return Progress::Done;
}

// {"do": "segment_seeds", "save": "seeds.json"} / {"load": "seeds.json"}: the Segment window's
// "Save seeds" / "Load seeds" (a loaded file's settings take effect; a growth on screen grows again).
ScriptInterpreter::Outcome ScriptInterpreter::segmentSeeds(Context& c) {
  SegmentController& s = c.model.segmenter();
  if (c.action.contains("save") == c.action.contains("load"))
    return fail("ui script: segment_seeds: give one of \"save\" and \"load\"");
  if (c.action.contains("save")) {
    if (auto st = s.saveSeeds(c.action.at("save").get<std::string>()); !st) return tl::unexpected(st.error());
    return Progress::Done;
  }
  auto loaded = s.loadSeeds(c.action.at("load").get<std::string>());
  if (!loaded) return tl::unexpected(loaded.error());
  return Progress::Done;
}

// {"do": "segment_review", "name": "liver", "state": "completed"}: a structure's review state
// (not_started, in_progress, completed, flagged), as its list entry in the Segment window sets it.
ScriptInterpreter::Outcome ScriptInterpreter::segmentReview(Context& c) {
  SegmentController& s = c.model.segmenter();
  auto label = s.labelNamed(c.action.at("name").get<std::string>());
  if (!label) return tl::unexpected(label.error());
  const std::string name = c.action.at("state").get<std::string>();
  const auto state = db::reviewStateNamed(name);
  if (!state)
    return fail("ui script: segment_review: \"state\" must be not_started, in_progress, completed or flagged, not '" +
                name + "'");
  if (auto st = s.setReviewState(*label, *state); !st) return tl::unexpected(st.error());
  return Progress::Done;
}

// {"do": "segment_tool", "tool": "paint", "brush_mm": 3}: the click's tool — seeds, threshold,
// paint (the current structure) or erase — as the Segment window's radio buttons choose it; with
// paint or erase, a "click" in the 3-D view paints where the ray meets the volume.
ScriptInterpreter::Outcome ScriptInterpreter::segmentTool(Context& c) {
  using Tool = SegmentController::Tool;
  SegmentController& s = c.model.segmenter();
  const std::string name = c.action.at("tool").get<std::string>();
  const std::pair<const char*, Tool> tools[] = {
      {"seeds", Tool::Seeds}, {"threshold", Tool::Threshold}, {"paint", Tool::Paint}, {"erase", Tool::Erase}};
  const auto it = std::find_if(std::begin(tools), std::end(tools), [&](const auto& t) { return name == t.first; });
  if (it == std::end(tools))
    return fail("ui script: segment_tool: \"tool\" must be seeds, threshold, paint or erase, not '" + name + "'");
  s.tool = it->second;
  if (c.action.contains("brush_mm")) s.brushMm = c.action.at("brush_mm").get<double>();
  return Progress::Done;
}

// {"do": "segment_slice", "axis": "z", "index": 40} (axis x, y, z or 0, 1, 2).
ScriptInterpreter::Outcome ScriptInterpreter::segmentSlice(Context& c) {
  const json& a = c.action.at("axis");
  int axis = -1;
  if (a.is_string()) {
    const std::string text = a.get<std::string>();
    axis = text == "x" ? 0 : text == "y" ? 1 : text == "z" ? 2 : -1;
    if (axis < 0) return fail("ui script: segment_slice: \"axis\" must be x, y or z, not '" + text + "'");
  } else {
    axis = a.get<int>();
  }
  if (auto st = c.model.segmenter().setSlice(axis, c.action.at("index").get<int>()); !st) return tl::unexpected(st.error());
  return Progress::Done;
}

// {"do": "segment_seed", "voxel": [i, j, k], "brush_mm": 1.5, "low": -1100, "high": -400}: seeds of
// the current label in the brush around the voxel, as a click in the slice paints them; with low
// and high only the values in that range joined to the voxel (the "seeds only in range" box), and
// the range stays set for later clicks; without them the range is cleared.
ScriptInterpreter::Outcome ScriptInterpreter::segmentSeed(Context& c) {
  SegmentController& s = c.model.segmenter();
  if (c.action.contains("brush_mm")) s.brushMm = c.action.at("brush_mm").get<double>();
  if (c.action.contains("low") != c.action.contains("high"))
    return fail("ui script: segment_seed: \"low\" and \"high\" go together");
  s.seedRange.reset();
  if (c.action.contains("low")) s.seedRange = {{c.action.at("low").get<double>(), c.action.at("high").get<double>()}};
  const auto v = c.action.at("voxel").get<std::vector<int>>();
  if (v.size() != 3) return fail("ui script: segment_seed: \"voxel\" must be [i, j, k]");
  auto painted = s.paintSeeds({v[0], v[1], v[2]});
  if (!painted) return tl::unexpected(painted.error());
  return Progress::Done;
}

// {"do": "segment_grow", "wait": true}: grow from seeds (on the editor's worker); with "wait" the
// script goes on once the growth is applied (the segment_grown event reports the voxels per label)
// and fails with the growth's error.
ScriptInterpreter::Outcome ScriptInterpreter::segmentGrow(Context& c) {
  SegmentController& s = c.model.segmenter();
  if (c.first) {
    if (auto st = s.grow(); !st) return tl::unexpected(st.error());
    if (!c.action.value("wait", true)) return Progress::Done;
  }
  if (s.growing()) return Progress::Running;
  if (s.growError()) return tl::unexpected(*s.growError());
  return Progress::Done;
}

// {"do": "segment_growth", "bone_only": true, "range": [lo, hi], "limit": false, "base_per_voxel": b,
// "window": [lo, hi], "smoothing": s, "defaults": true, "wait": true}: the Segment window's growth
// settings, each key as its widget sets it ("bone_only" as the "bone" button: the limit on, the
// data's bone range; "defaults" as "Data defaults", first); keys left out stay. A growth on screen
// grows again with them (the live preview); with "wait" the script goes on once it is applied.
ScriptInterpreter::Outcome ScriptInterpreter::segmentGrowth(Context& c) {
  SegmentController& s = c.model.segmenter();
  if (c.first) {
    const json& a = c.action;
    for (const auto& item : a.items()) {
      const std::string& key = item.key();
      static const char* known[] = {"do", "bone_only", "range", "limit", "base_per_voxel", "window", "smoothing", "defaults", "wait"};
      if (std::none_of(std::begin(known), std::end(known), [&](const char* k) { return key == k; }))
        return fail("ui script: segment_growth: unknown key \"" + key + "\"");
    }
    if (a.value("defaults", false)) s.resetGrowthSettings();
    SegmentController::GrowthSettings settings = s.growthSettings();
    const auto pair = [&](const char* key) -> Result<std::array<double, 2>> {
      const auto v = a.at(key).get<std::vector<double>>();
      if (v.size() != 2) return fail(std::string("ui script: segment_growth: \"") + key + "\" must be [low, high]");
      return std::array<double, 2>{v[0], v[1]};
    };
    if (a.value("bone_only", false)) settings.limitRange = true, settings.range = s.growthDefaults().boneRangeValues;
    if (a.contains("range")) {
      auto range = pair("range");
      if (!range) return tl::unexpected(range.error());
      settings.limitRange = true, settings.range = *range;
    }
    if (a.contains("limit")) settings.limitRange = a.at("limit").get<bool>();
    if (a.contains("window")) {
      auto window = pair("window");
      if (!window) return tl::unexpected(window.error());
      settings.window = *window;
    }
    if (a.contains("base_per_voxel")) settings.basePerVoxel = a.at("base_per_voxel").get<double>();
    if (a.contains("smoothing")) settings.smoothingVoxels = a.at("smoothing").get<double>();
    if (auto st = s.setGrowthSettings(settings); !st) return tl::unexpected(st.error());
    if (!a.value("wait", true)) return Progress::Done;
  }
  if (s.growing()) return Progress::Running;
  if (s.growError()) return tl::unexpected(*s.growError());
  return Progress::Done;
}

// {"do": "segment_system", "name": "mandible", "system": "skull bones"}: a structure's system
// (browsing group), as the Segment window's "system" field sets it; stored with segment_save.
ScriptInterpreter::Outcome ScriptInterpreter::segmentSystem(Context& c) {
  SegmentController& s = c.model.segmenter();
  auto label = s.labelNamed(c.action.at("name").get<std::string>());
  if (!label) return tl::unexpected(label.error());
  if (auto st = s.setSystem(*label, c.action.at("system").get<std::string>()); !st) return tl::unexpected(st.error());
  return Progress::Done;
}

// {"do": "segment_threshold", "voxel": [i, j, k], "low": 150, "high": 255, "min_diameter_mm": 0}:
// the connected region of values in the range under the voxel takes the current label (low and
// high default to the dataset's window).
ScriptInterpreter::Outcome ScriptInterpreter::segmentThreshold(Context& c) {
  SegmentController& s = c.model.segmenter();
  const auto v = c.action.at("voxel").get<std::vector<int>>();
  if (v.size() != 3) return fail("ui script: segment_threshold: \"voxel\" must be [i, j, k]");
  const auto window = s.valueWindow();
  auto done = s.thresholdIsland({v[0], v[1], v[2]}, c.action.value("low", window[0]), c.action.value("high", window[1]),
                                c.action.value("min_diameter_mm", 0.0));
  if (!done) return tl::unexpected(done.error());
  return Progress::Done;
}

// {"do": "segment_margin", "mm": 1.0} (negative: shrink) and {"do": "segment_hollow", "mm": 0.5}:
// the current structure.
ScriptInterpreter::Outcome ScriptInterpreter::segmentMargin(Context& c) {
  auto done = c.model.segmenter().margin(c.action.at("mm").get<double>());
  if (!done) return tl::unexpected(done.error());
  return Progress::Done;
}

// {"do": "segment_split", "min_diameter_mm": 0, "min_voxels": 1}: the current structure's pieces
// become structures of their own, as the Segment window's "Split islands" button.
ScriptInterpreter::Outcome ScriptInterpreter::segmentSplit(Context& c) {
  const double diameter = c.action.value("min_diameter_mm", 0.0);
  const int minVoxels = c.action.value("min_voxels", 1);
  if (minVoxels < 1) return fail("ui script: segment_split: \"min_voxels\" must be >= 1");
  auto done = c.model.segmenter().splitIslands(diameter, std::size_t(minVoxels));
  if (!done) return tl::unexpected(done.error());
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::segmentHollow(Context& c) {
  auto done = c.model.segmenter().hollow(c.action.at("mm").get<double>());
  if (!done) return tl::unexpected(done.error());
  return Progress::Done;
}

// {"do": "slices_open", "crosshair": [i, j, k], "label_alpha": 0.4}: shows the Slices window,
// through that voxel when given.
ScriptInterpreter::Outcome ScriptInterpreter::slicesOpen(Context& c) {
  SliceViews& slices = c.model.slices();
  slices.windowOpen = c.action.value("open", true);
  if (c.action.contains("label_alpha")) slices.labelAlpha = c.action.at("label_alpha").get<double>();
  if (c.action.contains("crosshair")) {
    const auto v = c.action.at("crosshair").get<std::vector<int>>();
    if (v.size() != 3) return fail("ui script: slices_open: \"crosshair\" must be [i, j, k]");
    if (auto st = slices.setCrosshair({v[0], v[1], v[2]}); !st) return tl::unexpected(st.error());
  }
  return Progress::Done;
}

// {"do": "segment_undo"}, {"do": "segment_redo"} (as Ctrl+Z and Ctrl+Shift+Z / Ctrl+Y in the
// Segment window) and {"do": "segment_clear_seeds"}.
ScriptInterpreter::Outcome ScriptInterpreter::segmentUndo(Context& c) {
  auto undone = c.model.segmenter().undo();
  if (!undone) return tl::unexpected(undone.error());
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::segmentRedo(Context& c) {
  auto redone = c.model.segmenter().redo();
  if (!redone) return tl::unexpected(redone.error());
  return Progress::Done;
}

ScriptInterpreter::Outcome ScriptInterpreter::segmentClearSeeds(Context& c) {
  c.model.segmenter().clearSeeds();
  return Progress::Done;
}

// {"do": "segment_save"} stores the labels into the dataset store (an imported dataset);
// {"do": "segment_save", "out": "labels.nii.gz", "names": "names.json"} exports them as a file
// (.nii, .nii.gz or .seg.nrrd).
ScriptInterpreter::Outcome ScriptInterpreter::segmentSave(Context& c) {
  SegmentController& s = c.model.segmenter();
  if (!c.action.contains("out")) {
    auto saved = s.saveToStore();
    if (!saved) return tl::unexpected(saved.error());
    return Progress::Done;
  }
  if (auto st = s.exportLabels(c.action.at("out").get<std::string>(), c.action.value("names", "")); !st)
    return tl::unexpected(st.error());
  return Progress::Done;
}

}  // namespace at::app
