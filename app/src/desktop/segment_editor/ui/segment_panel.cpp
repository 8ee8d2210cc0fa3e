// The Segment window: labels, the slice with seeds painted by clicking and dragging (or a
// threshold island under a click), the brush, margin / hollow, Grow / Undo / Redo / Clear seeds,
// and saving — each widget calling the SegmentController command the UI script's segment_*
// actions call.
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>

#include "ui/panels.h"
#include "segment_editor/segment_controller.h"
#include "core/printable_text.h"

namespace at::app {

namespace {

const ImVec4 kError{1, 0.5f, 0.4f, 1};

template <class T>
Status statusOf(const Result<T>& result) {
  return result ? Status{} : Status(tl::unexpected(result.error()));
}

// A button drawn disabled (greyed, not clickable) when `enabled` is false.
bool historyButton(const char* label, bool enabled) {
  ImGui::BeginDisabled(!enabled);
  const bool clicked = ImGui::Button(label);
  ImGui::EndDisabled();
  return clicked && enabled;
}

}  // namespace

void SegmentPanel::report(const Status& st) { error_ = st ? "" : st.error().message; }

void SegmentPanel::draw(SegmentController& editor, const PanelRect& where) {
  if (!editor.windowOpen || !editor.attached()) return;
  // Docked: a column at the window's right edge, its sections stacked (the slice as wide as the
  // column) and scrolled; floating: the controls left of the slice, sized to fit.
  const bool docked = where.docked();
  if (!beginPanel("Segment editor", &editor.windowOpen, where)) {
    ImGui::End();
    return;
  }
  const float line = ImGui::GetFontSize();
  if (!docked) ImGui::BeginGroup();  // the controls, left of the slice
  if (ImGui::CollapsingHeader("Labels", ImGuiTreeNodeFlags_DefaultOpen)) drawLabels(editor, docked ? 6 : 12);
  const bool sliceOpen = ImGui::CollapsingHeader("Slice", ImGuiTreeNodeFlags_DefaultOpen);
  if (sliceOpen) drawSliceControls(editor);
  // Docked, the slice is as wide as the column but leaves room for the tools below it.
  if (sliceOpen && docked) drawSlice(editor, std::min(ImGui::GetContentRegionAvail().x, 0.42f * where.h));
  if (ImGui::CollapsingHeader("Tools", ImGuiTreeNodeFlags_DefaultOpen)) drawTools(editor);
  if (ImGui::CollapsingHeader("Growth settings")) drawGrowthSettings(editor);
  if (ImGui::CollapsingHeader("Save and export", docked ? 0 : ImGuiTreeNodeFlags_DefaultOpen)) drawSaving(editor);
  ImGui::PushTextWrapPos(docked ? 0.0f : ImGui::GetCursorPosX() + line * 22);
  if (!editor.status().empty()) ImGui::TextWrapped("%s", editor.status().c_str());
  if (!error_.empty()) ImGui::TextColored(kError, "%s", error_.c_str());
  if (editor.growError()) ImGui::TextColored(kError, "%s", editor.growError()->message.c_str());
  ImGui::PopTextWrapPos();
  if (!docked) {
    ImGui::EndGroup();
    ImGui::SameLine();
    ImGui::BeginGroup();
    drawSlice(editor, line * 30);
    ImGui::EndGroup();
  }
  // Painting in the slice ends when the button is let go, wherever the mouse is.
  if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
    lastPainted_.reset();
    if (stroking_) editor.endStroke();
    stroking_ = false;
  }
  ImGui::End();
}

void SegmentPanel::drawLabels(SegmentController& editor, int listLines) {
  const auto perLabel = editor.seedsPerLabel();
  const auto seeded = [&](std::uint16_t label) {
    const auto it = perLabel.find(label);
    return it == perLabel.end() ? std::size_t(0) : it->second;
  };
  const float line = ImGui::GetFontSize();
  ImGui::TextUnformatted("Review state, name (seed voxels)");
  const float width = std::min(line * 26, ImGui::GetContentRegionAvail().x);
  ImGui::BeginChild("labels", ImVec2(width, line * float(listLines)), true);
  if (ImGui::RadioButton(("background (" + std::to_string(seeded(0)) + ")").c_str(), editor.currentLabel() == 0))
    report(editor.setCurrentLabel(0));
  for (const Structure& s : editor.structures()) {
    ImGui::PushID(s.label);
    // Its review state first (instructors only; a fixed column, whatever the name's length).
    const db::ReviewState state = editor.reviewState(s.label);
    ImGui::SetNextItemWidth(line * 7);
    if (ImGui::BeginCombo("##review", db::reviewStateText(state))) {
      for (db::ReviewState option : db::kReviewStates)
        if (ImGui::Selectable(db::reviewStateText(option), option == state)) report(editor.setReviewState(s.label, option));
      ImGui::EndCombo();
    }
    ImGui::SameLine();
    ImGui::ColorButton("##colour", ImVec4(s.colour[0], s.colour[1], s.colour[2], 1), ImGuiColorEditFlags_NoTooltip,
                       ImVec2(line, line));
    ImGui::SameLine();
    const std::string text = s.displayName + " (" + std::to_string(seeded(s.label)) + ")";
    if (ImGui::RadioButton(printableUiText(text).c_str(), editor.currentLabel() == s.label)) report(editor.setCurrentLabel(s.label));
    ImGui::PopID();
  }
  ImGui::EndChild();
  // The current structure's system (browsing group), stored with "Save into the dataset".
  for (const Structure& s : editor.structures()) {
    if (s.label != editor.currentLabel()) continue;
    if (systemLabel_ != s.label) systemLabel_ = s.label, system_ = s.system;
    ImGui::SetNextItemWidth(line * 12);
    if (ImGui::InputTextWithHint("system", "system, e.g. skull bones", &system_, ImGuiInputTextFlags_EnterReturnsTrue))
      report(editor.setSystem(s.label, system_));
    drawLabelGrowRange(editor, s.label);
  }
  ImGui::SetNextItemWidth(line * 12);
  ImGui::InputTextWithHint("##new", "new label name", &newLabel_);
  ImGui::SameLine();
  if (ImGui::Button("Add label") && !newLabel_.empty()) {
    auto added = editor.addLabel(newLabel_);
    report(statusOf(added));
    if (added) newLabel_.clear();
  }
}

void SegmentPanel::drawLabelGrowRange(SegmentController& editor, std::uint16_t label) {
  // The current structure's own grow range (a seeds file's "grow_range"): it keeps only voxels in
  // the range, grown by a growth that cannot leave it — "bone" for a thin bone that must not take
  // the soft tissue around it. A growth on screen grows again at once.
  const auto range = editor.labelGrowRange(label);
  const int kind = !range ? 0 : range->bone ? 1 : 2;
  static const char* kKinds[] = {"anywhere", "bone only", "only in range"};
  const float line = ImGui::GetFontSize();
  ImGui::SetNextItemWidth(line * 8);
  int chosen = kind;
  if (ImGui::Combo("label grows", &chosen, kKinds, 3) && chosen != kind) {
    if (chosen == 0) report(editor.setLabelGrowRange(label, std::nullopt));
    if (chosen == 1) report(editor.setLabelGrowRange(label, SegmentController::LabelGrowRange{std::nullopt, true}));
    if (chosen == 2) report(editor.setLabelGrowRange(label, SegmentController::LabelGrowRange{editor.valueWindow(), false}));
  }
  if (range && !range->bone && range->values) {
    float values[2] = {float((*range->values)[0]), float((*range->values)[1])};
    ImGui::SetNextItemWidth(line * 10);
    if (ImGui::InputFloat2("##labelrange", values, "%.0f", ImGuiInputTextFlags_EnterReturnsTrue))
      report(editor.setLabelGrowRange(label, SegmentController::LabelGrowRange{std::array<double, 2>{values[0], values[1]}, false}));
  }
}

void SegmentPanel::drawSliceControls(SegmentController& editor) {
  ImGui::TextUnformatted("radiological: the patient's left on the right; right-drag: grey window");
  // The three planes, each named with the voxel axis it crosses (x, y or z in the file's order).
  for (int plane = 0; plane < 3; ++plane) {
    const int axis = editor.axisOfPlane(PatientPlane(plane));
    if (plane > 0) ImGui::SameLine();
    const std::string label = std::string(planeName(PatientPlane(plane))) + " (" + char('x' + axis) + ")";
    if (ImGui::RadioButton(label.c_str(), editor.axis() == axis) && axis != editor.axis()) report(editor.showAxis(axis));
  }
  int index = editor.index();
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
  if (ImGui::SliderInt("index", &index, 0, std::max(0, editor.sliceCount() - 1))) report(editor.setSlice(editor.axis(), index));
  float brush = float(editor.brushMm);
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
  // 0 … 10 mm (on a µCT finer than 0.1 mm, the same voxels: 0 … 1 mm at 10 µm).
  const double scale = editor.brushScale();
  if (ImGui::SliderFloat("brush (mm)", &brush, 0.0f, float(10.0 * scale), scale < 1 ? "%.4f" : "%.1f",
                         scale < 1 ? ImGuiSliderFlags_NoRoundToFormat : ImGuiSliderFlags_None))
    editor.brushMm = brush;
}

void SegmentPanel::drawTools(SegmentController& editor) {
  // The click's tool: seeds, the threshold island under the click (the current structure), or
  // the brush painting the current structure / erasing labels (also on the 3-D view's surface).
  using Tool = SegmentController::Tool;
  const double scale = editor.brushScale();  // lengths kept voxel for voxel on a µCT finer than 0.1 mm
  const bool fine = scale < 1;
  const auto toolButton = [&](const char* text, Tool tool) {
    if (ImGui::RadioButton(text, editor.tool == tool)) editor.tool = tool;
  };
  toolButton("paint seeds", Tool::Seeds);
  ImGui::SameLine();
  toolButton("threshold island", Tool::Threshold);
  toolButton("paint label", Tool::Paint);
  ImGui::SameLine();
  toolButton("erase", Tool::Erase);
  if (editor.brushesInView()) ImGui::TextDisabled("  also on the 3-D view: click or drag (no orbit)");
  if (editor.tool == Tool::Seeds) {
    // A local threshold for seeds of any label (the background too): only the brush's voxels in
    // the range that join the clicked one.
    bool limited = editor.seedRange.has_value();
    if (ImGui::Checkbox("seeds only in range", &limited)) {
      const auto window = editor.valueWindow();
      editor.seedRange = limited ? std::optional<std::array<double, 2>>({window[0], window[1]}) : std::nullopt;
    }
    if (editor.seedRange) {
      float seedRange[2] = {float((*editor.seedRange)[0]), float((*editor.seedRange)[1])};
      ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
      if (ImGui::InputFloat2("seed range", seedRange, "%.0f")) editor.seedRange = {{seedRange[0], seedRange[1]}};
    }
  }
  if (editor.tool == Tool::Threshold) {
    if (!rangeSet_) {
      const auto window = editor.valueWindow();
      range_[0] = float(window[0] + 0.5 * (window[1] - window[0]));
      range_[1] = float(window[1]);
      rangeSet_ = true;
    }
    ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
    ImGui::InputFloat2("range", range_, "%.0f");
    ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
    float minDiameter = float(minDiameterMm_ * scale);
    if (ImGui::SliderFloat("cut bridges (mm)", &minDiameter, 0.0f, float(5.0 * scale), fine ? "%.4f" : "%.2f",
                           fine ? ImGuiSliderFlags_NoRoundToFormat : ImGuiSliderFlags_None))
      minDiameterMm_ = float(minDiameter / scale);
  }
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 6);
  float margin = float(marginMm_ * scale);
  if (ImGui::InputFloat("mm##margin", &margin, 0, 0, fine ? "%.4f" : "%.2f")) marginMm_ = float(margin / scale);
  margin = std::fabs(margin);
  ImGui::SameLine();
  if (ImGui::Button("Grow label")) report(statusOf(editor.margin(margin)));
  ImGui::SameLine();
  if (ImGui::Button("Shrink")) report(statusOf(editor.margin(-margin)));
  ImGui::SameLine();
  if (ImGui::Button("Hollow")) report(statusOf(editor.hollow(margin)));
  ImGui::SameLine();
  // Pieces of fewer than 27 voxels (a 3 × 3 × 3 speck) stay with the structure: a click must not
  // turn a noisy label's specks into hundreds of structures.
  if (ImGui::Button("Split islands")) report(statusOf(editor.splitIslands(minDiameterMm_ * scale, 27)));
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("the structure's disconnected pieces (bridges thinner than 'cut bridges' cut) become structures");

  if (ImGui::Button(editor.growing() ? "Grow again" : "Grow from seeds")) report(editor.grow());
  // Undo / redo: the buttons, and Ctrl+Z, Ctrl+Shift+Z or Ctrl+Y while this window has the
  // focus and no text field takes the keys (a field's own Ctrl+Z edits its text).
  const ImGuiIO& io = ImGui::GetIO();
  const bool keys = ImGui::IsWindowFocused(ImGuiFocusedFlags_RootAndChildWindows) && !io.WantTextInput && io.KeyCtrl;
  const bool zKey = keys && ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Z), false);
  const bool yKey = keys && ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Y), false);
  ImGui::SameLine();
  if (historyButton("Undo", editor.canUndo()) || (zKey && !io.KeyShift)) report(statusOf(editor.undo()));
  ImGui::SameLine();
  if (historyButton("Redo", editor.canRedo()) || (zKey && io.KeyShift) || yKey) report(statusOf(editor.redo()));
  ImGui::SameLine();
  if (ImGui::Button("Clear seeds")) editor.clearSeeds();
}

void SegmentPanel::drawGrowthSettings(SegmentController& editor) {
  // The growth's step cost: base per mm of travel plus the intensity change in the window (an
  // edge costs its contrast once). Defaults come from the data; a change grows again at once when
  // a growth is on screen (the live preview). "Grow only into" limits growth to a value range
  // (bone only by default: the data's bone range); voxels outside it are labelled only by paint.
  SegmentController::GrowthSettings s = editor.growthSettings();
  ImGui::TextWrapped("defaults from the data: %s", editor.growthDefaults().summary.c_str());
  float base = float(s.basePerVoxel);
  float window[2] = {float(s.window[0]), float(s.window[1])};
  float smoothing = float(s.smoothingVoxels);
  bool changed = false;
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
  changed |= ImGui::SliderFloat("base per voxel", &base, 0.0005f, 0.2f, "%.4f", ImGuiSliderFlags_Logarithmic);
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
  changed |= ImGui::InputFloat2("window", window, "%.0f", ImGuiInputTextFlags_EnterReturnsTrue);
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
  changed |= ImGui::SliderFloat("smoothing (voxels)", &smoothing, 0.0f, 3.0f, "%.1f");
  ImGui::TextDisabled("  lower base: labels follow edges further; window: the values that matter");
  bool limit = s.limitRange;
  float range[2] = {float(s.range[0]), float(s.range[1])};
  changed |= ImGui::Checkbox("grow only into", &limit);
  ImGui::SameLine();
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 10);
  changed |= ImGui::InputFloat2("##range", range, "%.0f", ImGuiInputTextFlags_EnterReturnsTrue);
  ImGui::SameLine();
  if (ImGui::SmallButton("bone")) {
    limit = true;
    range[0] = float(editor.growthDefaults().boneRangeValues[0]);
    range[1] = float(editor.growthDefaults().boneRangeValues[1]);
    changed = true;
  }
  if (changed) {  // latest wins: a drag regrows with the newest value, cancelling the one before
    s.basePerVoxel = base;
    s.window = {window[0], window[1]};
    s.smoothingVoxels = smoothing;
    s.limitRange = limit;
    s.range = {range[0], range[1]};
    report(editor.setGrowthSettings(s));
  }
  if (ImGui::Button("Data defaults")) editor.resetGrowthSettings();
}

void SegmentPanel::drawSaving(SegmentController& editor) {
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 16);
  ImGui::InputTextWithHint("##seeds", "seeds.json", &seedsPath_);
  ImGui::SameLine();
  if (ImGui::Button("Save seeds")) report(editor.saveSeeds(seedsPath_));
  ImGui::SameLine();
  if (ImGui::Button("Load seeds")) report(statusOf(editor.loadSeeds(seedsPath_)));
  if (ImGui::Button("Save into the dataset")) report(statusOf(editor.saveToStore()));
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 16);
  ImGui::InputTextWithHint("##export", "labels.nii.gz or .seg.nrrd", &exportPath_);
  ImGui::SameLine();
  if (ImGui::Button("Export")) {
    std::string names;
    if (exportPath_.size() > 7 && exportPath_.ends_with(".nii.gz")) names = exportPath_.substr(0, exportPath_.size() - 7) + ".names.json";
    report(editor.exportLabels(exportPath_, names));
  }
}

void SegmentPanel::drawSlice(SegmentController& editor, float side) {
  using Tool = SegmentController::Tool;
  // The picture: each voxel a block of 3 × 3 texels (the texture is filtered linearly: blocks keep
  // voxel edges sharp when it is magnified).
  const int scale = 3;
  if (!texture_ || revision_ != editor.revision()) {
    revision_ = editor.revision();
    auto image = editor.sliceImage(scale);
    if (!image) {
      error_ = image.error().message;
    } else {
      if (!texture_) {
        auto texture = render::gl::ImageTexture::create();
        if (texture) texture_ = std::move(*texture);
        else error_ = texture.error().message;
      }
      if (texture_) report(texture_->upload(toRgba(*image)));
    }
  }
  if (!texture_ || !texture_->handle() || texture_->width() <= 0) return;
  // At the voxels' aspect, the longer side `side` long; a right drag sets the grey window.
  const auto mouse = drawSlicePane("##slice", *texture_, editor.slicePixelMm(), side,
                                   [&](double dx, double dy) { editor.dragWindow(dx, dy); });
  drawEdgeLetters(editor.sliceLayout());
  if (!mouse || !ImGui::IsMouseDown(ImGuiMouseButton_Left)) return;
  const auto voxel = editor.voxelAtPixel(scale, mouse->x, mouse->y);
  if (!voxel || voxel == lastPainted_) return;
  lastPainted_ = voxel;
  if (editor.tool == Tool::Threshold) {  // one island per click
    if (ImGui::IsMouseClicked(ImGuiMouseButton_Left))
      report(statusOf(editor.thresholdIsland(*voxel, range_[0], range_[1], minDiameterMm_ * editor.brushScale())));
  } else if (editor.tool == Tool::Seeds) {
    report(statusOf(editor.paintSeeds(*voxel)));
  } else {  // a drag's dabs: one edit
    if (!stroking_) editor.beginStroke();
    stroking_ = true;
    report(statusOf(editor.brushAtVoxel(*voxel)));
  }
}

}  // namespace at::app
