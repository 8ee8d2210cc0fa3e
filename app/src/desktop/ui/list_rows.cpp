#include "ui/list_rows.h"

#include <imgui.h>

#include "core/printable_text.h"

namespace at::app {

bool listRowSelectable(int index, const std::string& words, bool selected) {
  ImGui::PushID(index);
  const bool clicked = ImGui::Selectable(printableUiText(words).c_str(), selected);
  ImGui::PopID();
  return clicked;
}

bool listRowCheckbox(int index, const std::string& words, bool* on) {
  ImGui::PushID(index);
  const bool toggled = ImGui::Checkbox(printableUiText(words).c_str(), on);
  ImGui::PopID();
  return toggled;
}

}  // namespace at::app
