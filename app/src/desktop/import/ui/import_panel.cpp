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
  // How the values are read (kept with the dataset): the unit, and a rescale for values the file
  // does not calibrate (a raw volume, a CT stored without its rescale: intercept -1024).
  const char* units[] = {"as the file says", "CT in HU", "plain intensities"};
  int unit = form.intensity == IntensityChoice::Hounsfield ? 1 : form.intensity == IntensityChoice::Plain ? 2 : 0;
  if (ImGui::Combo("values", &unit, units, 3))
    form.intensity = unit == 1 ? IntensityChoice::Hounsfield : unit == 2 ? IntensityChoice::Plain : IntensityChoice::Auto;
  bool rescale = form.intercept.has_value() || form.slope.has_value();
  if (ImGui::Checkbox("rescale the values: value x slope + intercept", &rescale)) {
    form.intercept = rescale ? std::optional<double>(0) : std::nullopt;
    form.slope = rescale ? std::optional<double>(1) : std::nullopt;
  }
  if (rescale) {
    double intercept = form.intercept.value_or(0), slope = form.slope.value_or(1);
    if (ImGui::InputDouble("intercept", &intercept, 0, 0, "%g")) form.intercept = intercept;
    if (ImGui::InputDouble("slope", &slope, 0, 0, "%g")) form.slope = slope;
  }
  // What the file does not say (a NIfTI or NRRD MR): the import refuses a code DICOM does not know.
  ImGui::InputTextWithHint("modality", "optional, for a file that records none: MR, PT, US, CT, ...", &form.modality);
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
