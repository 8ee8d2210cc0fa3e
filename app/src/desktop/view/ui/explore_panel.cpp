#include <algorithm>
#include <cmath>
#include <cstdio>

#include <imgui.h>
#include <imgui_stdlib.h>

#include "core/strings.h"
#include "ui/list_rows.h"
#include "ui/panels.h"
#include "segment_editor/segment_controller.h"
#include "core/printable_text.h"

namespace at::app {

namespace {
const char* kViews[] = {"anterior", "posterior", "lateral_left", "lateral_right", "superior", "inferior"};
const char* kViewButtons[] = {"Ant", "Post", "L", "R", "Sup", "Inf"};
}  // namespace

void ExplorePanel::draw(DesktopModel& model, const Status& status) {
  const ViewLayout& layout = model.layout();
  ExploreState& explore = model.explore();
  const Dataset& dataset = model.dataset();
  // Full height at the left edge; its right edge may be dragged (the view takes the rest). Wider
  // on a window of 1200 pixels or more, where the view keeps enough room.
  const float scale = layout.uiScale, windowH = float(layout.windowH);
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2((layout.windowW >= 1200 ? 380.0f : 320.0f) * scale, windowH), ImGuiCond_FirstUseEver);
  const float widest = std::max(260 * scale, float(layout.windowW) * 0.6f);
  ImGui::SetNextWindowSizeConstraints(ImVec2(260 * scale, windowH), ImVec2(widest, windowH));
  ImGui::Begin("Explore", nullptr, ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoCollapse | ImGuiWindowFlags_NoTitleBar);
  width_ = ImGui::GetWindowWidth();
  ImGui::TextUnformatted("Anatomy Tutor - Explore");
  // The Dataset menu: the datasets here, by name (imported ones, the phantom, the skull CT).
  if (ImGui::SmallButton("Dataset")) ImGui::OpenPopup("dataset_menu");
  if (ImGui::BeginPopup("dataset_menu")) {
    for (const std::string& name : model.datasetChoices())
      if (ImGui::MenuItem(printableUiText(name).c_str(), nullptr, name == model.courseDatasetId()))
        if (auto st = model.switchDataset(name); !st) model.message(st.error().message);
    ImGui::EndPopup();
  }
  ImGui::SameLine();
  ImGui::TextDisabled("%s", dataset.displayName.empty() ? printableUiText(dataset.id).c_str() : printableUiText(dataset.displayName).c_str());
  // What the user must keep in mind about this dataset's pictures: under its name, not among the
  // notes at the panel's foot (below the fold of a small window).
  if (const auto& caution = model.datasetCaution()) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextColored(ImVec4(1, 0.82f, 0.4f, 1), "%s", printableUiText(*caution).c_str());
    ImGui::PopTextWrapPos();
  }
  if (ImGui::SmallButton("Studies...")) model.study().coordinatorOpen = true;
  ImGui::SameLine();
  if (ImGui::SmallButton("Import...")) model.imports().windowOpen = true;
  ImGui::SameLine();
  if (ImGui::SmallButton("Segment...")) model.segmenter().windowOpen = model.slices().windowOpen = true;
  // The instructor's windows on a line of their own (the panel's narrowest width keeps them whole).
  if (ImGui::SmallButton("Courses...")) model.courseEditor().windowOpen = true;
  ImGui::SameLine();
  if (ImGui::SmallButton("Analytics...")) model.analytics().windowOpen = true;
  ImGui::Separator();
  lessons_.draw(model.lessons(), model.exams(), float(layout.windowH) * 0.4f);
  ImGui::Separator();

  // While a question would be given away by a name (throughout a quiz-only lesson and an exam),
  // no structure name is shown: not the selected or hovered one, nor the browser.
  const bool hideNames = model.namesHidden();
  const Structure* selected = hideNames ? nullptr : dataset.findStructureByLabel(explore.selected());
  const Structure* hovered = hideNames ? nullptr : dataset.findStructureByLabel(explore.hovered());
  if (selected) {
    ImGui::TextColored(ImVec4(1, 0.75f, 0.3f, 1), "%s", printableUiText(selected->displayName).c_str());
    ImGui::TextDisabled("%s", printableUiText(selected->system).c_str());
    ImGui::PushTextWrapPos(0);
    ImGui::TextUnformatted(printableUiText(selected->description).c_str());
    ImGui::PopTextWrapPos();
  }
  ImGui::Text("Hover: %s", hovered ? printableUiText(hovered->displayName).c_str() : "-");
  ImGui::Separator();

  if (explore.wholeVolume()) {  // an unlabelled scan: no structure to select, field or bare mode
    ImGui::PushTextWrapPos(0);
    ImGui::TextDisabled("No labelled structures: the whole volume is shown with a transfer function "
                        "derived from its intensities. Label it with Segment...");
    ImGui::PopTextWrapPos();
  } else if (model.expertOn()) {  // the view shows the expert's preset: its mode and t are set there
    const render::Preset& edited = model.expert().preset();
    ImGui::TextDisabled("%s, t %.2f: set in the Expert panel", render::toString(edited.mode), double(edited.t));
  } else {
    int mode = explore.bare() ? 1 : 0;
    if (ImGui::RadioButton("WDT preset", &mode, 0)) explore.setBare(false);
    ImGui::SameLine();
    if (ImGui::RadioButton("Bare preset", &mode, 1)) explore.setBare(true);
    float t = explore.t();
    if (ImGui::SliderFloat("t (context)", &t, 0, 1, "%.2f")) explore.setT(t);
  }
  if (bool on = model.expertOn(); ImGui::Checkbox("Expert", &on)) model.setExpert(on);
  ImGui::SameLine();
  if (ImGui::Button("Slices...")) model.slices().windowOpen = true;  // axial, coronal, sagittal

  ImGui::TextUnformatted("View");
  for (int i = 0; i < 6; ++i) {
    if (i) ImGui::SameLine();
    if (ImGui::SmallButton(kViewButtons[i]))
      if (auto st = model.setView(kViews[i]); !st) model.message(st.error().message);
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("%s", kViews[i]);
  }
  ClipSettings clip = explore.clip();
  bool clipChanged = ImGui::Checkbox("Clipping plane", &clip.on);
  if (clip.on) {
    const char* axes[] = {"left-right", "anterior-posterior", "inferior-superior"};
    clipChanged |= ImGui::Combo("axis", &clip.axis, axes, 3);
    clipChanged |= ImGui::Checkbox("flip side", &clip.flip);
    // At least 5 mm, kept voxel for voxel on a µCT finer than 0.1 mm (volume/geometry.h), with
    // the finer steps such a scan needs.
    const Vec3& spacing = dataset.volume.geometry.spacingMm;
    const double voxelScale = fineVoxelScale(std::max({spacing[0], spacing[1], spacing[2]}));
    const bool fine = voxelScale < 1;
    const float range = float(std::max(5.0 * voxelScale, explore.camera().distanceMm));
    clipChanged |= ImGui::SliderFloat("offset mm", &clip.offsetMm, -range, range, fine ? "%.4f" : "%.1f",
                                      fine ? ImGuiSliderFlags_NoRoundToFormat : ImGuiSliderFlags_None);
  }
  if (clipChanged) explore.setClip(clip);
  ImGui::Separator();

  if (!hideNames) ImGui::InputTextWithHint("##search", "search structures", &search_);
  drawStructures(model, hideNames);

  drawQuality(model);
  drawFieldProgress(model);
  ImGui::PushTextWrapPos(0);
  ImGui::TextDisabled("%s", status.glDescription.c_str());
  for (const std::string& n : model.notes()) ImGui::TextDisabled("%s", printableUiText(n).c_str());  // information, not a problem
  for (const std::string& m : model.messages()) ImGui::TextColored(ImVec4(1, 0.5f, 0.4f, 1), "%s", printableUiText(m).c_str());
  ImGui::PopTextWrapPos();
  ImGui::End();
}

void ExplorePanel::drawStructures(DesktopModel& model, bool hideNames) {
  const std::string query = str::lower(search_);
  // What is left above the status lines, but never less than eight rows: the panel scrolls then.
  const float rows = ImGui::GetTextLineHeightWithSpacing() * 8;
  ImGui::BeginChild("structures", ImVec2(0, std::max(rows, ImGui::GetContentRegionAvail().y - statusHeight(model))), true);
  if (hideNames) {
    ImGui::PushTextWrapPos(0);
    ImGui::TextDisabled("(structure names are hidden during the question or exam)");
    ImGui::PopTextWrapPos();
  }
  for (const auto& [system, list] : model.explore().bySystem()) {
    if (hideNames) break;
    std::vector<const Structure*> shown;
    for (const Structure* s : list)
      if (query.empty() || str::lower(s->displayName).find(query) != std::string::npos ||
          str::lower(s->id).find(query) != std::string::npos || str::lower(s->description).find(query) != std::string::npos)
        shown.push_back(s);
    if (shown.empty()) continue;
    ImGui::SetNextItemOpen(true, ImGuiCond_Once);
    if (!query.empty()) ImGui::SetNextItemOpen(true);
    if (ImGui::TreeNode(printableUiText(system).c_str())) {
      for (const Structure* s : shown) {
        if (listRowSelectable(int(s->label), s->displayName, s->label == model.explore().selected())) model.select(s->label);
        if (ImGui::IsItemHovered() && !s->description.empty()) {
          ImGui::BeginTooltip();
          ImGui::PushTextWrapPos(ImGui::GetFontSize() * 25);
          ImGui::TextUnformatted(printableUiText(s->description).c_str());
          ImGui::PopTextWrapPos();
          ImGui::EndTooltip();
        }
      }
      ImGui::TreePop();
    }
  }
  ImGui::EndChild();
}

float ExplorePanel::statusHeight(const DesktopModel& model) const {
  // The status lines, the GL description (two lines) and the messages as they wrap, so that the
  // messages stay visible; at most half of what is left for the structure list and them.
  float height = ImGui::GetTextLineHeightWithSpacing() * 5.5f;
  const float wrap = ImGui::GetContentRegionAvail().x;
  for (const auto* list : {&model.notes(), &model.messages()})
    for (const std::string& m : *list)
      height += ImGui::CalcTextSize(m.c_str(), nullptr, false, wrap).y + ImGui::GetStyle().ItemSpacing.y;
  return std::min(height, std::max(ImGui::GetTextLineHeightWithSpacing() * 5.5f, ImGui::GetContentRegionAvail().y * 0.5f));
}

// What the view shows: a coarse level while moving, the full level being refined, or full quality
// (with its resolution where slow GL renders it below the view's).
void ExplorePanel::drawQuality(DesktopModel& model) {
  const FrameScheduler& scheduler = model.scheduler();
  const double frameMs = model.recorder().lastFrameMs();
  const int scalePercent = int(std::lround(100 * scheduler.fullScale() * model.options().renderScale));
  if (scheduler.renderedLevel() >= kFullLevel && scalePercent < 100)
    ImGui::TextDisabled("full quality at %d%% resolution, frame %.0f ms", scalePercent, frameMs);
  else if (scheduler.renderedLevel() >= kFullLevel)
    ImGui::TextDisabled("full quality, frame %.0f ms", frameMs);
  else if (scheduler.refining())
    ImGui::TextDisabled("refining %.0f%%, frame %.0f ms", 100 * scheduler.refinedFraction(), frameMs);
  else
    ImGui::TextDisabled("level %d/%d%s, frame %.0f ms", std::max(0, scheduler.renderedLevel()), kFullLevel,
                        scheduler.interacting() ? " (moving)" : "", frameMs);
}

// The running field's progress; a full-resolution one can be cancelled (the coarse one stays).
void ExplorePanel::drawFieldProgress(DesktopModel& model) {
  FieldView& fields = model.fields();
  const auto running = fields.running();
  if (!running || running->elapsedMs < 250) {  // quick fields need no bar
    if (fields.declined() && !running) {
      ImGui::TextDisabled("full resolution cancelled");
      ImGui::SameLine();
      if (ImGui::SmallButton("Compute it")) fields.allowDeclined();
    } else {
      ImGui::PushTextWrapPos(0);
      ImGui::TextDisabled("%s", fields.busy() ? "computing a distance field..." : fields.status().c_str());
      ImGui::PopTextWrapPos();
    }
    return;
  }
  const int ds = running->request.params.downsample;
  char text[200];
  std::snprintf(text, sizeof text, "%s field: pass %d/%d, %.1f s", ds == 1 ? "full-res" : ("1/" + std::to_string(ds)).c_str(),
                running->passesDone, running->passesPlanned, running->elapsedMs / 1000);
  const float fraction = float(running->passesDone) / float(std::max(1, running->passesPlanned));
  ImGui::ProgressBar(fraction, ImVec2(ds == 1 ? -60 * model.layout().uiScale : -1, 0), text);
  if (ds == 1) {
    ImGui::SameLine();
    if (ImGui::SmallButton("Cancel##field")) model.cancelFineField();
    if (ImGui::IsItemHovered()) ImGui::SetTooltip("Stop the full-resolution field; the coarse one stays on screen");
  }
}

}  // namespace at::app
