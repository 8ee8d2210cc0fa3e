#include <imgui.h>
#include <imgui_stdlib.h>

#include "ui/panels.h"

namespace at::app {

void ImportPanel::draw(ImportController& imports, float x, float y) {
  if (!imports.windowOpen) return;
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_Appearing);
  const float width = ImGui::GetFontSize() * 48;
  ImGui::SetNextWindowSizeConstraints(ImVec2(width, 0), ImVec2(width, 10000));
  if (!ImGui::Begin("Import dataset", &imports.windowOpen, ImGuiWindowFlags_AlwaysAutoResize)) {
    ImGui::End();
    return;
  }
  const auto progress = imports.progress();
  ImportRequest& form = imports.form;
  ImGui::BeginDisabled(progress.has_value());
  ImGui::PushItemWidth(-ImGui::GetFontSize() * 4.5f);
  ImGui::InputTextWithHint("volume", "DICOM folder, .nii, .nii.gz, .nrrd, .nhdr or .inv3", &form.volumePath);
  ImGui::InputTextWithHint("labels", "optional: label map (those formats or DICOM SEG)", &form.labelsPath);
  ImGui::InputTextWithHint("names", "optional: JSON {\"1\": \"spleen\", ...}", &form.namesPath);
  ImGui::InputTextWithHint("name", "what the dataset will be called", &form.name);
  ImGui::InputText("species", &form.species);
  ImGui::PopItemWidth();
  if (ImGui::Button("Import"))
    if (auto st = imports.start(form); !st) error_ = st.error().message;
  ImGui::EndDisabled();

  if (progress) {
    error_.clear();
    ImGui::ProgressBar(progress->fraction, ImVec2(-90, 0), progress->text.c_str());
    ImGui::SameLine();
    ImGui::BeginDisabled(progress->cancelling);
    if (ImGui::Button("Cancel")) imports.cancel();
    ImGui::EndDisabled();
  } else if (!error_.empty() || !imports.status().empty()) {
    const bool failed = !error_.empty() || imports.failed();
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(failed ? ImVec4(1, 0.5f, 0.4f, 1) : ImVec4(0.6f, 1, 0.6f, 1), "%s",
                       error_.empty() ? imports.status().c_str() : error_.c_str());
    ImGui::PopTextWrapPos();
  }
  if (!progress && imports.canOpen() && ImGui::Button("Open in explore view")) imports.requestOpen();
  ImGui::End();
}

}  // namespace at::app
