// The volume view's orientation marker and scale bar (render/overlay.h's geometry), drawn with
// ImGui over the view as the `render` command draws them into its images: the patient axes in the
// bottom-left corner (L/R red, P/A green, S/I blue, the far ends dimmer), the scale bar in mm in
// the bottom-right.
#include <algorithm>
#include <array>
#include <cmath>

#include <imgui.h>

#include "ui/panels.h"
#include "render/overlay.h"

namespace at::app {

void drawViewOverlay(const render::Camera& camera, float left, float top, float width, float height, float uiScale) {
  if (width < 120 || height < 120) return;
  ImDrawList* draw = ImGui::GetBackgroundDrawList();
  const float unit = std::max(1.0f, uiScale);
  const float margin = 14 * unit, arm = 26 * unit;
  const ImU32 text = IM_COL32(235, 235, 235, 255), shadow = IM_COL32(0, 0, 0, 200);
  const std::array<std::array<int, 3>, 3> colours{{{230, 90, 80}, {110, 200, 110}, {100, 150, 240}}};

  const ImVec2 centre(left + margin + arm + 12 * unit, top + height - margin - arm - 12 * unit);
  const ImU32 backing = IM_COL32(0, 0, 0, 140);  // so that the marks read over white bone too
  const float reach = arm + 18 * unit;
  draw->AddRectFilled(ImVec2(centre.x - reach, centre.y - reach), ImVec2(centre.x + reach, centre.y + reach), backing,
                      6 * unit);
  struct End {
    double depth;
    int axis, sign;
  };
  const std::array<render::MarkerAxis, 3> axes = render::orientationMarker(camera);
  std::array<End, 6> ends{};
  for (int a = 0; a < 3; ++a) {
    ends[std::size_t(2 * a)] = {axes[std::size_t(a)].towardViewer, a, 1};
    ends[std::size_t(2 * a + 1)] = {-axes[std::size_t(a)].towardViewer, a, -1};
  }
  std::sort(ends.begin(), ends.end(), [](const End& p, const End& q) { return p.depth < q.depth; });  // far ends first
  for (const End& e : ends) {
    const render::MarkerAxis& m = axes[std::size_t(e.axis)];
    const auto& c = colours[std::size_t(e.axis)];
    const int dim = e.depth < 0 ? 2 : 1;
    const ImVec2 tip(centre.x + float(e.sign * m.dx) * arm, centre.y + float(e.sign * m.dy) * arm);
    draw->AddLine(centre, tip, IM_COL32(c[0] / dim, c[1] / dim, c[2] / dim, 255), 2.5f * unit);
    if (std::hypot(m.dx, m.dy) < 0.25) continue;  // pointing at the viewer: its letter would sit on the centre
    const char letter[2] = {e.sign > 0 ? m.positive : m.negative, 0};
    const ImVec2 size = ImGui::CalcTextSize(letter);
    const ImVec2 at(centre.x + float(e.sign * m.dx) * (arm + 9 * unit) - size.x / 2,
                    centre.y + float(e.sign * m.dy) * (arm + 9 * unit) - size.y / 2);
    draw->AddText(ImVec2(at.x + 1, at.y + 1), shadow, letter);
    draw->AddText(at, e.depth < 0 ? IM_COL32(150, 150, 150, 255) : text, letter);
  }

  const render::ScaleBar bar = render::scaleBar(camera, int(width), int(height));
  const float x1 = left + width - margin, x0 = x1 - float(bar.pixels), y = top + height - margin - 4 * unit;
  const ImVec2 size = ImGui::CalcTextSize(bar.label.c_str());
  const ImVec2 at(0.5f * (x0 + x1) - size.x / 2, y - 6 * unit - size.y);
  draw->AddRectFilled(ImVec2(std::min(x0, at.x) - 6 * unit, at.y - 4 * unit), ImVec2(x1 + 6 * unit, y + 6 * unit),
                      backing, 4 * unit);
  draw->AddLine(ImVec2(x0 + 1, y + 1), ImVec2(x1 + 1, y + 1), shadow, 3 * unit);
  draw->AddLine(ImVec2(x0, y), ImVec2(x1, y), text, 3 * unit);
  for (float x : {x0, x1}) draw->AddLine(ImVec2(x, y - 5 * unit), ImVec2(x, y + 2 * unit), text, 2 * unit);
  draw->AddText(ImVec2(at.x + 1, at.y + 1), shadow, bar.label.c_str());
  draw->AddText(at, text, bar.label.c_str());
}

}  // namespace at::app
