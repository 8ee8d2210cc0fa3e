#include "ui/widget_rects.h"

#include <cstdint>
#include <utility>

#include <imgui.h>

namespace at::app {

namespace {
nlohmann::json& drawing() {
  static nlohmann::json rects = nlohmann::json::object();
  return rects;
}
std::uint64_t& frames() {
  static std::uint64_t n = 0;
  return n;
}
nlohmann::json& drawn() {
  static nlohmann::json rects = nlohmann::json::object();
  return rects;
}
}  // namespace

void noteWidget(const std::string& name, const std::string& text) {
  const ImVec2 a = ImGui::GetItemRectMin(), b = ImGui::GetItemRectMax();
  ImDrawList* list = ImGui::GetWindowDrawList();
  const ImVec2 c0 = list->GetClipRectMin(), c1 = list->GetClipRectMax();
  nlohmann::json& w = drawing()[name] = {{"rect", {a.x, a.y, b.x, b.y}}, {"clip", {c0.x, c0.y, c1.x, c1.y}}};
  if (!text.empty()) w["text"] = text;
}

void clearWidgetRects() {
  drawn() = std::exchange(drawing(), nlohmann::json::object());
  ++frames();
}

nlohmann::json widgetRects() { return {{"frame", frames()}, {"widgets", drawn()}}; }

}  // namespace at::app
