// The Segment window: labels, the slice with seeds painted by clicking and dragging (or a
// threshold island under a click), the brush, margin / hollow, Grow / Undo / Clear seeds, and saving — each widget calling the SegmentController command the UI
// script's segment_* actions call.
#include <imgui.h>
#include <imgui_stdlib.h>

#include <algorithm>
#include <cmath>

#include "panels.h"
#include "segment_controller.h"

namespace at::app {

namespace {

const ImVec4 kError{1, 0.5f, 0.4f, 1};

template <class T>
Status statusOf(const Result<T>& result) {
  return result ? Status{} : Status(tl::unexpected(result.error()));
}

}  // namespace

void SegmentPanel::draw(SegmentController& editor, float x, float y) {
  if (!editor.windowOpen || !editor.attached()) return;
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_Appearing);
  if (!ImGui::Begin("Segment editor", &editor.windowOpen, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::End();
    return;
  }
  const auto report = [this](const Status& st) { error_ = st ? "" : st.error().message; };

  // Labels: background and the structures; a new one by name.
  const auto perLabel = editor.seedsPerLabel();
  const auto seeded = [&](std::uint16_t label) {
    const auto it = perLabel.find(label);
    return it == perLabel.end() ? std::size_t(0) : it->second;
  };
  const float line = ImGui::GetFontSize();
  ImGui::BeginGroup();  // the controls, left of the slice
  ImGui::TextUnformatted("Paint seeds of");
  ImGui::BeginChild("labels", ImVec2(line * 22, line * 12), true);
  if (ImGui::RadioButton(("background (" + std::to_string(seeded(0)) + ")").c_str(), editor.currentLabel() == 0))
    report(editor.setCurrentLabel(0));
  for (const Structure& s : editor.structures()) {
    ImGui::PushID(s.label);
    ImGui::ColorButton("##colour", ImVec4(s.colour[0], s.colour[1], s.colour[2], 1), ImGuiColorEditFlags_NoTooltip,
                       ImVec2(ImGui::GetFontSize(), ImGui::GetFontSize()));
    ImGui::SameLine();
    const std::string text = s.displayName + " (" + std::to_string(seeded(s.label)) + ")";
    if (ImGui::RadioButton(text.c_str(), editor.currentLabel() == s.label)) report(editor.setCurrentLabel(s.label));
    ImGui::PopID();
  }
  ImGui::EndChild();
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 12);
  ImGui::InputTextWithHint("##new", "new label name", &newLabel_);
  ImGui::SameLine();
  if (ImGui::Button("Add label") && !newLabel_.empty()) {
    auto added = editor.addLabel(newLabel_);
    report(added ? Status{} : Status(tl::unexpected(added.error())));
    if (added) newLabel_.clear();
  }

  // The slice.
  ImGui::TextUnformatted("Slice (x sagittal, y coronal, z axial)");
  ImGui::TextUnformatted("  axis");
  for (int a = 0; a < 3; ++a) {
    ImGui::SameLine();
    if (ImGui::RadioButton(a == 0 ? "x" : a == 1 ? "y" : "z", editor.axis() == a) &&
        a != editor.axis())
      report(editor.showAxis(a));
  }
  int index = editor.index();
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
  if (ImGui::SliderInt("index", &index, 0, std::max(0, editor.sliceCount() - 1))) report(editor.setSlice(editor.axis(), index));
  float brush = float(editor.brushMm);
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
  if (ImGui::SliderFloat("brush (mm)", &brush, 0.0f, 10.0f, "%.1f")) editor.brushMm = brush;

  // The click's tool: seeds, or the threshold island under the click (the current structure).
  ImGui::RadioButton("paint seeds", &tool_, 0);
  ImGui::SameLine();
  ImGui::RadioButton("threshold island", &tool_, 1);
  if (tool_ == 1) {
    if (!rangeSet_) {
      const auto window = editor.valueWindow();
      range_[0] = float(window[0] + 0.5 * (window[1] - window[0]));
      range_[1] = float(window[1]);
      rangeSet_ = true;
    }
    ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
    ImGui::InputFloat2("range", range_, "%.0f");
    ImGui::SetNextItemWidth(ImGui::GetFontSize() * 14);
    ImGui::SliderFloat("cut bridges (mm)", &minDiameterMm_, 0.0f, 5.0f, "%.2f");
  }
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 6);
  ImGui::InputFloat("mm##margin", &marginMm_, 0, 0, "%.2f");
  ImGui::SameLine();
  if (ImGui::Button("Grow label")) report(statusOf(editor.margin(std::fabs(marginMm_))));
  ImGui::SameLine();
  if (ImGui::Button("Shrink")) report(statusOf(editor.margin(-std::fabs(marginMm_))));
  ImGui::SameLine();
  if (ImGui::Button("Hollow")) report(statusOf(editor.hollow(std::fabs(marginMm_))));

  if (ImGui::Button(editor.growing() ? "Grow again" : "Grow from seeds")) report(editor.grow());
  ImGui::SameLine();
  if (ImGui::Button("Undo")) {
    auto undone = editor.undo();
    report(undone ? Status{} : Status(tl::unexpected(undone.error())));
  }
  ImGui::SameLine();
  if (ImGui::Button("Clear seeds")) editor.clearSeeds();
  if (ImGui::Button("Save into the dataset")) {
    auto saved = editor.saveToStore();
    report(saved ? Status{} : Status(tl::unexpected(saved.error())));
  }
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 16);
  ImGui::InputTextWithHint("##export", "labels.nii.gz or .seg.nrrd", &exportPath_);
  ImGui::SameLine();
  if (ImGui::Button("Export")) {
    std::string names;
    if (exportPath_.size() > 7 && exportPath_.ends_with(".nii.gz")) names = exportPath_.substr(0, exportPath_.size() - 7) + ".names.json";
    report(editor.exportLabels(exportPath_, names));
  }
  ImGui::PushTextWrapPos(ImGui::GetCursorPosX() + line * 22);
  if (!editor.status().empty()) ImGui::TextWrapped("%s", editor.status().c_str());
  if (!error_.empty()) ImGui::TextColored(kError, "%s", error_.c_str());
  if (editor.growError()) ImGui::TextColored(kError, "%s", editor.growError()->message.c_str());
  ImGui::PopTextWrapPos();
  ImGui::EndGroup();
  ImGui::SameLine();
  ImGui::BeginGroup();
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
  if (texture_ && texture_->handle() && texture_->width() > 0) {
    // At the voxels' aspect (mm per picture pixel along each side), the longer side 30 lines long.
    const auto pixelMm = editor.slicePixelMm();
    const double widthMm = texture_->width() * pixelMm[0], heightMm = texture_->height() * pixelMm[1];
    const double perMm = ImGui::GetFontSize() * 30 / std::max(widthMm, heightMm);
    const float zoomX = float(perMm * pixelMm[0]), zoomY = float(perMm * pixelMm[1]);
    const ImVec2 size(float(texture_->width()) * zoomX, float(texture_->height()) * zoomY);
    const ImVec2 origin = ImGui::GetCursorScreenPos();
    ImGui::Image(reinterpret_cast<ImTextureID>(texture_->handle()), size);
    if (ImGui::IsItemHovered() && ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
      const ImVec2 m = ImGui::GetMousePos();
      if (auto voxel = editor.voxelAtPixel(scale, (m.x - origin.x) / zoomX, (m.y - origin.y) / zoomY);
          voxel && voxel != lastPainted_) {
        lastPainted_ = voxel;
        if (tool_ == 1) {  // one island per click
          if (ImGui::IsMouseClicked(ImGuiMouseButton_Left))
            report(statusOf(editor.thresholdIsland(*voxel, range_[0], range_[1], minDiameterMm_)));
        } else {
          report(statusOf(editor.paintSeeds(*voxel)));
        }
      }
    }
    if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) lastPainted_.reset();
  }

  ImGui::EndGroup();
  ImGui::End();
}

}  // namespace at::app
