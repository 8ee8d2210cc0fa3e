// The Slices window: three panes (sagittal, coronal, axial) of SliceViews through the crosshair,
// with the segment editor's labels; each widget calls the SliceViews command.
#include <imgui.h>

#include <algorithm>

#include "ui/panels.h"
#include "segment_editor/segment_controller.h"

namespace at::app {

namespace {

const char* kPaneNames[3] = {"sagittal", "coronal", "axial"};

}  // namespace

// The pane's patient direction letters at the middle of its four edges, inside the picture.
void drawEdgeLetters(const SliceLayout& layout) {
  const ImVec2 lo = ImGui::GetItemRectMin(), hi = ImGui::GetItemRectMax();
  ImDrawList* draw = ImGui::GetWindowDrawList();
  const ImU32 colour = IM_COL32(255, 220, 40, 255);
  const float pad = 3, h = ImGui::GetTextLineHeight(), w = ImGui::CalcTextSize("M").x;
  const float midX = (lo.x + hi.x - w) / 2, midY = (lo.y + hi.y - h) / 2;
  const auto put = [&](float x, float y, char c) {
    const char text[2] = {c, 0};
    draw->AddText(ImVec2(x, y), colour, text);
  };
  put(lo.x + pad, midY, layout.left);
  put(hi.x - pad - w, midY, layout.right);
  put(midX, lo.y + pad, layout.top);
  put(midX, hi.y - pad - h, layout.bottom);
}

render::RgbaImage toRgba(const RgbImage& image) {
  render::RgbaImage rgba(image.width, image.height);
  for (std::size_t i = 0; i < std::size_t(image.width) * std::size_t(image.height); ++i) {
    for (std::size_t c = 0; c < 3; ++c) rgba.rgba[i * 4 + c] = image.rgb[i * 3 + c];
    rgba.rgba[i * 4 + 3] = 255;
  }
  return rgba;
}

bool beginPanel(const char* title, bool* open, const PanelRect& where) {
  if (where.docked()) {
    ImGui::SetNextWindowPos(ImVec2(where.x, where.y));
    ImGui::SetNextWindowSize(ImVec2(where.w, where.h));
    return ImGui::Begin(title, open, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  }
  ImGui::SetNextWindowPos(ImVec2(where.x, where.y), ImGuiCond_Appearing);
  return ImGui::Begin(title, open, ImGuiWindowFlags_AlwaysAutoResize);
}

std::optional<PaneMouse> drawSlicePane(const char* id, const render::gl::ImageTexture& texture, std::array<double, 2> pixelMm,
                                       float side, const std::function<void(double, double)>& grey) {
  const double widthMm = texture.width() * pixelMm[0], heightMm = texture.height() * pixelMm[1];
  const double perMm = side / std::max(widthMm, heightMm);
  const float zoomX = float(perMm * pixelMm[0]), zoomY = float(perMm * pixelMm[1]);
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  const ImVec2 size(float(texture.width()) * zoomX, float(texture.height()) * zoomY);
  ImGui::Image(reinterpret_cast<ImTextureID>(texture.handle()), size);
  // A button over the picture takes its clicks and drags (else a drag would move the window).
  ImGui::SetCursorScreenPos(origin);
  ImGui::InvisibleButton(id, size, ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight);
  if (ImGui::IsItemActive() && ImGui::IsMouseDragging(ImGuiMouseButton_Right)) {
    const ImVec2 d = ImGui::GetIO().MouseDelta;
    grey(d.x, d.y);
  }
  if (!ImGui::IsItemHovered()) return std::nullopt;
  const ImVec2 m = ImGui::GetMousePos();
  return PaneMouse{(m.x - origin.x) / zoomX, (m.y - origin.y) / zoomY};
}

void SlicesPanel::draw(DesktopModel& model, const PanelRect& where) {
  SliceViews& slices = model.slices();
  if (!slices.windowOpen || !slices.attached()) return;
  // Docked: a strip under the view (the segment editor docked beside it), the panes filling it.
  const bool docked = where.docked();
  if (!beginPanel("Slices", &slices.windowOpen, where)) {
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
  ImGui::SameLine(0, ImGui::GetFontSize() * 2);
  ImGui::TextDisabled("radiological: patient's left on the screen's right");
  // Each voxel a block of 2 × 2 texels (linear filtering keeps voxel edges sharp when magnified).
  const int scale = 2;
  // The longer side of each pane: three side by side in a docked strip, under a line of names.
  const ImGuiStyle& style = ImGui::GetStyle();
  const float side = docked ? std::max(32.0f, std::min((ImGui::GetContentRegionAvail().x - 2 * style.ItemSpacing.x) / 3,
                                                       ImGui::GetContentRegionAvail().y - ImGui::GetTextLineHeightWithSpacing() -
                                                           style.ItemSpacing.y))
                            : ImGui::GetFontSize() * 16;
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
      const auto mouse = drawSlicePane(kPaneNames[axis], *texture, slices.pixelMm(axis), side,
                                       [&](double dx, double dy) { slices.dragWindow(dx, dy); });
      drawEdgeLetters(slices.layout(axis));
      if (mouse && ImGui::IsMouseDown(ImGuiMouseButton_Left)) slices.clickPane(axis, scale, mouse->x, mouse->y);
    }
    ImGui::EndGroup();
  }
  if (!error_.empty()) ImGui::TextColored(ImVec4(1, 0.5f, 0.4f, 1), "%s", error_.c_str());
  ImGui::End();
}

}  // namespace at::app
