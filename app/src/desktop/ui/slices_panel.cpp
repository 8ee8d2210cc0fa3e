// The Slices window: three panes (sagittal, coronal, axial) of SliceViews through the crosshair,
// with the segment editor's labels; each widget calls the SliceViews command.
#include <imgui.h>

#include <algorithm>

#include "panels.h"
#include "segment_controller.h"

namespace at::app {

namespace {

const char* kPaneNames[3] = {"sagittal (x)", "coronal (y)", "axial (z)"};

}  // namespace

render::RgbaImage toRgba(const RgbImage& image) {
  render::RgbaImage rgba(image.width, image.height);
  for (std::size_t i = 0; i < std::size_t(image.width) * std::size_t(image.height); ++i) {
    for (std::size_t c = 0; c < 3; ++c) rgba.rgba[i * 4 + c] = image.rgb[i * 3 + c];
    rgba.rgba[i * 4 + 3] = 255;
  }
  return rgba;
}

void SlicesPanel::draw(DesktopModel& model, float x, float y) {
  SliceViews& slices = model.slices();
  if (!slices.windowOpen || !slices.attached()) return;
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_Appearing);
  if (!ImGui::Begin("Slices", &slices.windowOpen, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::End();
    return;
  }
  const SegmentController& editor = model.segmenter();
  float alpha = float(slices.labelAlpha);
  ImGui::SetNextItemWidth(ImGui::GetFontSize() * 12);
  if (ImGui::SliderFloat("label opacity", &alpha, 0.0f, 1.0f, "%.2f")) slices.labelAlpha = alpha;
  const auto& c = slices.crosshair();
  ImGui::SameLine(0, ImGui::GetFontSize() * 2);
  ImGui::Text("crosshair (%d, %d, %d); right-drag: window", c[0], c[1], c[2]);
  // Each voxel a block of 2 × 2 texels (linear filtering keeps voxel edges sharp when magnified).
  const int scale = 2;
  const float side = ImGui::GetFontSize() * 16;  // the longer side of each pane
  const std::uint64_t key = slices.revision() * 1000003ull + editor.revision() * 131ull + std::uint64_t(alpha * 1000);
  for (int axis = 0; axis < 3; ++axis) {
    if (axis) ImGui::SameLine();
    ImGui::BeginGroup();
    ImGui::TextUnformatted(kPaneNames[axis]);
    auto& texture = textures_[std::size_t(axis)];
    if (!texture || drawn_[std::size_t(axis)] != key) {
      drawn_[std::size_t(axis)] = key;
      auto image = slices.pane(axis, scale, &editor.labels(), editor.structures());
      if (!image) {
        error_ = image.error().message;
      } else {
        if (!texture)
          if (auto made = render::gl::ImageTexture::create()) texture = std::move(*made);
        if (texture)
          if (auto st = texture->upload(toRgba(*image)); !st) error_ = st.error().message;
      }
    }
    if (texture && texture->handle() && texture->width() > 0) {
      const auto mm = slices.pixelMm(axis);
      const double widthMm = texture->width() * mm[0], heightMm = texture->height() * mm[1];
      const double perMm = side / std::max(widthMm, heightMm);
      const float zoomX = float(perMm * mm[0]), zoomY = float(perMm * mm[1]);
      const ImVec2 origin = ImGui::GetCursorScreenPos();
      ImGui::Image(reinterpret_cast<ImTextureID>(texture->handle()),
                   ImVec2(float(texture->width()) * zoomX, float(texture->height()) * zoomY));
      if (ImGui::IsItemHovered()) {
        const ImVec2 m = ImGui::GetMousePos();
        if (ImGui::IsMouseDown(ImGuiMouseButton_Left))
          slices.clickPane(axis, scale, (m.x - origin.x) / zoomX, (m.y - origin.y) / zoomY);
        if (ImGui::IsMouseDragging(ImGuiMouseButton_Right)) {
          const ImVec2 d = ImGui::GetIO().MouseDelta;
          slices.dragWindow(d.x, d.y);
        }
      }
    }
    ImGui::EndGroup();
  }
  if (!error_.empty()) ImGui::TextColored(ImVec4(1, 0.5f, 0.4f, 1), "%s", error_.c_str());
  ImGui::End();
}

}  // namespace at::app
