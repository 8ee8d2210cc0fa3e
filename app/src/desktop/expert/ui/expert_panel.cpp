#include <algorithm>
#include <array>
#include <cmath>

#include <imgui.h>
#include <imgui_stdlib.h>

#include "core/strings.h"
#include "ui/panels.h"

namespace at::app {

namespace {
ImU32 colourOf(const render::Rgba& c, float alpha = 1) { return ImGui::ColorConvertFloat4ToU32(ImVec4(c[0], c[1], c[2], alpha)); }
}  // namespace

bool ExpertPanel::splineEditor(TfEditor& editor, const char* id, bool data, float width, float height) {
  std::vector<render::TfPoint>& pts = data ? editor.editable().dataTf : editor.editable().distanceTf;
  // The shown x range: the dataset's HU range (data) or 0..1, widened to hold every point.
  double x0 = data ? editor.huMin() : 0.0, x1 = data ? editor.huMax() : 1.0;
  x0 = std::min(x0, pts.front().x);
  x1 = std::max(x1, pts.back().x);
  ImGui::InvisibleButton(id, ImVec2(width, height), ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight);
  const ImVec2 p0 = ImGui::GetItemRectMin(), p1 = ImGui::GetItemRectMax();
  const auto toPx = [&](double x, float a) {
    return ImVec2(p0.x + float((x - x0) / (x1 - x0)) * (p1.x - p0.x), p1.y - a * (p1.y - p0.y));
  };
  const ImVec2 mouse = ImGui::GetMousePos();
  const double mouseX = x0 + double((mouse.x - p0.x) / (p1.x - p0.x)) * (x1 - x0);
  const float mouseA = std::clamp((p1.y - mouse.y) / (p1.y - p0.y), 0.0f, 1.0f);

  ImDrawList* dl = ImGui::GetWindowDrawList();
  dl->AddRectFilled(p0, p1, IM_COL32(25, 25, 30, 255));
  const std::vector<float>& histogram = editor.histogram();
  if (data && !histogram.empty()) {
    const float bw = (p1.x - p0.x) * float((editor.huMax() - editor.huMin()) / (x1 - x0)) / float(histogram.size());
    const float hx = toPx(editor.huMin(), 0).x;
    for (std::size_t i = 0; i < histogram.size(); ++i)
      if (histogram[i] > 0)
        dl->AddRectFilled(ImVec2(hx + bw * float(i), p1.y - histogram[i] * (p1.y - p0.y)), ImVec2(hx + bw * float(i + 1), p1.y),
                          IM_COL32(80, 80, 95, 255));
  }
  if (auto tf = render::TransferFunction1D::fromPoints(pts)) {
    const int n = std::max(2, int(width / 2));
    ImVec2 prev;
    for (int i = 0; i < n; ++i) {
      const double x = x0 + (x1 - x0) * i / (n - 1);
      const render::Rgba c = tf->evaluate(x);
      const ImVec2 q = toPx(x, c[3]);
      dl->AddLine(ImVec2(q.x, p1.y), ImVec2(q.x, p1.y - 4), colourOf(c));
      if (i) dl->AddLine(prev, q, IM_COL32(230, 230, 230, 255), 1.5f);
      prev = q;
    }
  }
  for (const render::TfPoint& p : pts) {
    const ImVec2 q = toPx(p.x, p.rgba[3]);
    dl->AddCircleFilled(q, 5, colourOf(p.rgba));
    dl->AddCircle(q, 5, IM_COL32(255, 255, 255, 255));
  }

  bool edited = false;
  const double xTol = 7.0 * (x1 - x0) / double(p1.x - p0.x);
  const double aTol = 7.0 / double(p1.y - p0.y);
  const auto hit = render::hitTestTfPoint(pts, mouseX, mouseA, xTol, aTol);
  const ImGuiIO& io = ImGui::GetIO();
  if (ImGui::IsItemHovered()) {
    if (ImGui::IsMouseClicked(ImGuiMouseButton_Left)) {
      if (hit && !io.KeyCtrl) {
        dragging_ = Selection{data, *hit};
      } else if (ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left) || io.KeyCtrl) {
        render::Rgba c = render::TransferFunction1D::fromPoints(pts)->evaluate(mouseX);
        c[3] = mouseA;
        if (auto i = editor.addPoint(data, mouseX, c)) {
          dragging_ = Selection{data, *i};
          edited = true;
        }
      }
    }
    if (ImGui::IsMouseClicked(ImGuiMouseButton_Right) && hit) {
      menuFor_ = Selection{data, *hit};
      ImGui::OpenPopup(id);
    }
    if (hit) ImGui::SetTooltip("x %.3f  opacity %.2f", pts[*hit].x, double(pts[*hit].rgba[3]));
  }
  if (dragging_ && dragging_->data == data) {
    if (!ImGui::IsMouseDown(ImGuiMouseButton_Left)) {
      dragging_.reset();
    } else if (io.MouseDelta.x != 0 || io.MouseDelta.y != 0) {
      if (editor.movePoint(data, dragging_->index, mouseX, mouseA)) edited = true;
    }
  }
  if (ImGui::BeginPopup(id)) {
    if (menuFor_ && menuFor_->data == data && menuFor_->index < pts.size()) {
      const std::size_t i = menuFor_->index;
      ImGui::Text("point %zu at x = %.3f", i, pts[i].x);
      if (ImGui::MenuItem("Delete", nullptr, false, pts.size() > 2)) {
        if (editor.deletePoint(data, i)) edited = true;
        menuFor_.reset();
        ImGui::CloseCurrentPopup();
      } else {
        render::Rgba c = pts[i].rgba;
        if (ImGui::ColorPicker4("colour", c.data(), ImGuiColorEditFlags_AlphaBar) && editor.setColour(data, i, c)) edited = true;
      }
    }
    ImGui::EndPopup();
  }
  return edited;
}

bool ExpertPanel::draw(TfEditor& editor, float x, float width, float height) {
  if (!editor.active()) return false;
  ImGui::SetNextWindowPos(ImVec2(x, 0));
  ImGui::SetNextWindowSize(ImVec2(width, height));
  ImGui::Begin("Expert", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse);
  bool edited = false;
  const float w = ImGui::GetContentRegionAvail().x;
  ImGui::TextUnformatted("Data TF (HU; bars: log histogram)");
  edited |= splineEditor(editor, "##data_tf", true, w, 120);
  ImGui::TextUnformatted("Distance TF (normalised distance)");
  edited |= splineEditor(editor, "##distance_tf", false, w, 90);
  ImGui::TextDisabled("drag: move; double/ctrl-click: add; right-click: menu");

  // The other parameters are edited on a copy and handed over validated.
  ImGui::PushItemWidth(w * 0.55f);
  render::Preset p = editor.preset();
  bool changed = false;
  const auto& modes = render::allRenderModes();
  if (ImGui::BeginCombo("mode", render::toString(p.mode))) {
    for (render::RenderMode m : modes)
      if (ImGui::Selectable(render::toString(m), m == p.mode) && m != p.mode) {
        editor.switchMode(m);  // the mode's own preset (or this session's edits in it)
        p = editor.preset();
        edited = true;
      }
    ImGui::EndCombo();
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("each mode starts from its own preset; edits in a mode are kept when you switch back");
  changed |= ImGui::SliderFloat("t (context)", &p.t, 0, 1, "%.2f");
  changed |= ImGui::SliderFloat("alpha f(x)", &p.alpha, 1.01f, 10, "%.2f");
  changed |= ImGui::DragFloat("lighting alpha", &p.lightingAlpha, 0.01f, 0, 100, "%.3f");
  changed |= ImGui::DragFloat("lighting beta", &p.lightingBeta, 0.01f, 0, 100, "%.3f");
  int rule = p.weightRule == "trapezoid" ? 1 : 0;
  const char* rules[] = {"entering", "trapezoid"};
  if (ImGui::Combo("weight rule", &rule, rules, 2)) {
    p.weightRule = rules[rule];
    changed = true;
  }
  std::array<float, 2> win = p.huWindow;
  if (ImGui::DragFloat2("HU window", win.data(), 5, -32768, 32767, "%.0f") && win[0] < win[1]) {
    p.huWindow = win;
    changed = true;
  }
  changed |= ImGui::DragFloat("weight base", &p.weightBase, 0.001f, 0, 10, "%.3f");
  p.lightingAlpha = std::max(0.0f, p.lightingAlpha);
  p.lightingBeta = std::max(0.0f, p.lightingBeta);
  p.weightBase = std::max(0.0f, p.weightBase);
  if (changed) {
    if (auto st = editor.setParameters(p); !st) saveStatus_ = st.error().message;
    else edited = true;
  }

  ImGui::Separator();
  ImGui::InputText("name", &saveName_);
  ImGui::InputTextWithHint("export", "optional: PATH.json", &exportPath_);
  if (ImGui::Button("Save as")) {
    const Status st = editor.saveAs(saveName_, exportPath_.empty() ? std::nullopt : std::optional<std::string>(exportPath_));
    saveStatus_ = st ? "saved '" + str::identifier(saveName_) + "'" : st.error().message;
  }
  ImGui::PushTextWrapPos(0);
  ImGui::TextDisabled("%s", saveStatus_.c_str());
  ImGui::PopTextWrapPos();
  ImGui::PopItemWidth();
  ImGui::End();
  return edited;
}

}  // namespace at::app
