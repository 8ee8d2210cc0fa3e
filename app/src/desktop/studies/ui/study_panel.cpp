#include <algorithm>
#include <cstring>

#include <imgui.h>
#include <imgui_internal.h>
#include <imgui_stdlib.h>

#include "ui/panels.h"
#include "render/image.h"
#include "core/printable_text.h"

namespace at::app {

namespace {
using json = nlohmann::json;
// The visible part of an ImGui label (before "##").
std::string visible(const std::string& label) { return label.substr(0, label.find("##")); }
const ImVec4 kError{1, 0.5f, 0.4f, 1};
}  // namespace

// ---------------------------------------------------------------------------------------------
// Participant window

void StudyPanel::text(const std::string& s) {
  labels_.push_back(s);
  ImGui::TextUnformatted(printableUiText(s).c_str());
}

void StudyPanel::textWrapped(const std::string& s) {
  labels_.push_back(s);
  ImGui::PushTextWrapPos(0);
  ImGui::TextUnformatted(printableUiText(s).c_str());
  ImGui::PopTextWrapPos();
}

bool StudyPanel::button(const std::string& label) {
  labels_.push_back(visible(label));
  return ImGui::Button(label.c_str());
}

bool StudyPanel::radio(const std::string& label, int* value, int mine) {
  labels_.push_back(visible(label));
  return ImGui::RadioButton(label.c_str(), value, mine);
}

void StudyPanel::drawParticipant(StudyController& study, float width, float height) {
  if (!study.participantActive()) return;
  const bool newScreen = study.takeNewScreen();
  if (announce_ && !labels_.empty()) {
    // The screen drawn last frame is now on screen: print its labels and the visible windows —
    // before a trial that changed since (a script acting within one long frame) replaces it.
    json windows = json::array();
    for (ImGuiWindow* w : ImGui::GetCurrentContext()->Windows)
      if (w->WasActive && !(w->Flags & ImGuiWindowFlags_ChildWindow) && std::strncmp(w->Name, "Debug##", 7) != 0)
        windows.push_back(visible(w->Name));  // top-level windows, tooltips and popups included
    study.announce({{"event", "study_screen"}, {"labels", labels_}, {"windows", windows}});
    announce_ = false;
  }
  if (newScreen) announce_ = true;  // announced once drawn
  labels_.clear();
  StudyController::Participant& s = *study.participant();
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(width, height));
  ImGui::Begin("Preference study", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                   ImGuiWindowFlags_NoTitleBar);
  if (!s.trial) {
    text("Thank you!");
    textWrapped("All " + std::to_string(s.participant.trials.size()) + " structures are rated. Your answers are saved.");
    if (button("Close")) study.closeParticipant();
    ImGui::End();
    return;
  }
  const db::StudyTrial& trial = s.participant.trials[*s.trial];
  const std::size_t n = s.participant.trials.size();
  text("Structure " + std::to_string(trial.position + 1) + " of " + std::to_string(n));
  ImGui::ProgressBar(float(trial.position) / float(std::max<std::size_t>(1, n)), ImVec2(-1, 0), "");
  textWrapped("Compare the two views of the highlighted structure. Switch with the buttons or the keys A and B.");
  for (char side : {'A', 'B'}) {
    if (side == 'B') ImGui::SameLine();
    const bool on = s.side == side;
    if (on) ImGui::PushStyleColor(ImGuiCol_Button, ImGui::GetStyleColorVec4(ImGuiCol_ButtonActive));
    if (button(std::string("View ") + side)) study.showSide(side);
    if (on) ImGui::PopStyleColor();
  }
  text(std::string("Now showing: view ") + s.side);
  ImGui::Separator();
  // The protocol's anchors once, then each item on the scale.
  for (const auto& [value, anchor] : s.protocol.scale.anchors) text(std::to_string(value) + " = " + anchor);
  ImGui::Separator();
  // Ratings open once the side on screen has been drawn at full quality (not a coarse image still
  // refining); the note is not one of the screen's recorded labels (it changes frame by frame).
  const bool ready = study.readyToRate();
  if (!ready) ImGui::TextDisabled("Drawing view %c at full quality...", s.side);
  for (const auto& item : s.protocol.items) {
    textWrapped(item.wording);
    int rating = s.ratings[item.id];
    if (!ready) ImGui::BeginDisabled();
    for (int v = s.protocol.scale.min; v <= s.protocol.scale.max; ++v) {
      if (v > s.protocol.scale.min) ImGui::SameLine();
      if (radio(std::to_string(v) + "##" + item.id, &rating, v)) (void)study.rate(item.id, v);
    }
    if (!ready) ImGui::EndDisabled();
    ImGui::Spacing();
  }
  text("Comment (optional)");
  ImGui::InputTextMultiline("##comment", &s.comment, ImVec2(-1, ImGui::GetTextLineHeight() * 3));
  const bool allRated = study.allRated();
  if (!allRated) ImGui::BeginDisabled();
  const bool next = button("Next");
  if (!allRated) ImGui::EndDisabled();
  if (next) {
    // The detailed error may name the study: it goes to the log, the participant sees a plain note.
    if (auto st = study.nextTrial(); !st) {
      std::fprintf(stderr, "anatomy-tutor: %s\n", st.error().message.c_str());
      s.saveFailed = true;
    } else {
      s.saveFailed = false;
    }
  }
  if (study.participantActive() && s.saveFailed) textWrapped("Your answers could not be saved. Please tell the study coordinator.");
  // Leaves participant mode; answers up to the last Next are saved, and starting the same
  // participant again resumes at the first unrated structure.
  ImGui::SameLine(ImGui::GetWindowWidth() - 80);
  if (button("Pause")) study.closeParticipant();
  ImGui::End();
}

// ---------------------------------------------------------------------------------------------
// Coordinator window

void StudyPanel::summaryTable(const StudyController& study) {
  if (!study.summary() || study.summary()->items.empty()) return;
  const quiz::StudySummary& sum = *study.summary();
  const int columns = 1 + int(sum.columns.size());
  if (!ImGui::BeginTable("table2", columns, ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit))
    return;
  ImGui::TableSetupColumn("item");
  for (const std::string& c : sum.columns) ImGui::TableSetupColumn(c.c_str());
  ImGui::TableHeadersRow();
  for (std::size_t i = 0; i < sum.items.size(); ++i) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(printableUiText(sum.items[i]).c_str());
    for (std::size_t c = 0; c < sum.columns.size(); ++c) {
      ImGui::TableNextColumn();
      const quiz::SummaryCell& cell = sum.at(i, c);
      const quiz::LikertSummary& st = cell.stats;
      if (st.n == 0) {
        ImGui::TextDisabled("n = 0");
        continue;
      }
      ImGui::Text("%.2f +/- %.2f (n=%zu)", st.mean, st.sd, st.n);
      ImGui::Text("CI [%.2f, %.2f] p=%.3g", st.ciLow, st.ciHigh, st.pValue);
      if (cell.preferred != "none") ImGui::TextColored(ImVec4(0.5f, 1, 0.5f, 1), "prefers %s", cell.preferred.c_str());
    }
  }
  ImGui::EndTable();
}

void StudyPanel::summaryChart(StudyController& study) {
  if (chartRevision_ != study.chartRevision() || !chart_) {
    const RgbImage* chart = study.chart();
    if (!chart) {
      if (!study.chartError().empty()) ImGui::TextColored(kError, "%s", study.chartError().c_str());
      return;
    }
    chartRevision_ = study.chartRevision();
    render::RgbaImage rgba(chart->width, chart->height);
    for (std::size_t i = 0; i < std::size_t(chart->width) * std::size_t(chart->height); ++i) {
      for (std::size_t c = 0; c < 3; ++c) rgba.rgba[i * 4 + c] = chart->rgb[i * 3 + c];
      rgba.rgba[i * 4 + 3] = 255;
    }
    if (!chart_) {
      auto texture = render::gl::ImageTexture::create();
      if (!texture) {
        chartError_ = texture.error().message;
        return;
      }
      chart_ = std::move(*texture);
    }
    if (auto st = chart_->upload(rgba); !st) chartError_ = st.error().message;
  }
  if (!chartError_.empty()) ImGui::TextColored(kError, "%s", chartError_.c_str());
  if (!chart_ || !chart_->handle() || chart_->width() <= 0) return;
  const float w = std::min(ImGui::GetContentRegionAvail().x, float(chart_->width()));
  ImGui::Image(reinterpret_cast<ImTextureID>(chart_->handle()), ImVec2(w, w * float(chart_->height()) / float(chart_->width())));
}

void StudyPanel::drawCoordinator(StudyController& study, float x, float y) {
  if (!study.coordinatorOpen || study.participantActive()) return;
  if (study.studies().empty() && study.message().empty()) study.refreshStudies();
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_Appearing);
  ImGui::SetNextWindowSize(ImVec2(760, 620), ImGuiCond_Appearing);
  if (!ImGui::Begin("Studies (coordinator)", &study.coordinatorOpen)) {
    ImGui::End();
    return;
  }
  std::string& error = coordinatorError_;
  if (ImGui::Button("Refresh")) {
    error.clear();
    study.refreshStudies();
  }
  ImGui::SameLine();
  const quiz::StudyProtocol* selected = study.selectedStudy();
  ImGui::SetNextItemWidth(320);
  if (ImGui::BeginCombo("study", selected ? printableUiText(selected->id).c_str() : "(no study)")) {
    for (const quiz::StudyProtocol& p : study.studies())
      if (ImGui::Selectable(printableUiText(p.id).c_str(), &p == selected))
        if (auto st = study.selectStudy(p.id); !st) error = st.error().message;
    ImGui::EndCombo();
  }
  if (!study.message().empty()) ImGui::TextColored(kError, "%s", study.message().c_str());
  if (!error.empty()) ImGui::TextColored(kError, "%s", error.c_str());
  selected = study.selectedStudy();
  if (!selected) {
    ImGui::End();
    return;
  }
  const quiz::StudyProtocol& p = *selected;
  ImGui::PushTextWrapPos(0);
  ImGui::TextDisabled("%s", printableUiText(p.title).c_str());
  ImGui::PopTextWrapPos();
  ImGui::Text("%zu structures, %zu items, dataset %s", p.structures.size(), p.items.size(), printableUiText(p.dataset).c_str());

  if (ImGui::CollapsingHeader("Participants", ImGuiTreeNodeFlags_DefaultOpen)) {
    if (study.completion().empty()) ImGui::TextDisabled("nobody enrolled yet");
    for (const db::StudyCompletion& c : study.completion())
      ImGui::Text("%-16s %-12s %3d/%d ratings  %s", printableUiText(c.participantId).c_str(), printableUiText(c.group).c_str(), c.ratingsGiven,
                  c.ratingsExpected, c.complete ? "complete" : "in progress");
    ImGui::SetNextItemWidth(160);
    ImGui::InputTextWithHint("##pid", "participant id", &participantId_);
    if (!p.groups.empty()) {
      groupIndex_ = std::clamp(groupIndex_, 0, int(p.groups.size()) - 1);
      ImGui::SameLine();
      ImGui::SetNextItemWidth(140);
      if (ImGui::BeginCombo("##group", printableUiText(p.groups[std::size_t(groupIndex_)]).c_str())) {
        for (int i = 0; i < int(p.groups.size()); ++i)
          if (ImGui::Selectable(printableUiText(p.groups[std::size_t(i)]).c_str(), i == groupIndex_)) groupIndex_ = i;
        ImGui::EndCombo();
      }
      ImGui::SameLine();
      if (ImGui::Button("Start participant session")) {
        const std::string id = p.id, group = p.groups[std::size_t(groupIndex_)];
        if (auto st = study.startParticipant(id, participantId_, group); !st) error = st.error().message;
      }
    }
  }
  if (ImGui::CollapsingHeader("Export", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::SetNextItemWidth(360);
    ImGui::InputText("folder", &outDir_);
    ImGui::SameLine();
    const StudyExport* running = study.runningExport();
    const bool busy = running && !running->done();
    if (busy) ImGui::BeginDisabled();
    if (ImGui::Button("Export")) (void)study.startExport(outDir_);  // a failure shows as the status
    if (busy) ImGui::EndDisabled();
    running = study.runningExport();
    if (running) {
      ImGui::ProgressBar(float(running->written()) / float(std::max<std::size_t>(1, running->fileCount())),
                         ImVec2(busy ? -80 : -1, 0), study.exportStatus().c_str());
      if (busy) {
        ImGui::SameLine();
        if (ImGui::Button("Cancel##export")) study.cancelExport();
      }
    } else if (!study.exportStatus().empty()) {
      ImGui::TextColored(study.exportFailed() ? kError : ImVec4(1, 1, 1, 1), "%s", study.exportStatus().c_str());
    }
  }
  if (ImGui::CollapsingHeader("Summary (Table 2: 1 = prefer WDT ... 5 = prefer bare)", ImGuiTreeNodeFlags_DefaultOpen)) {
    summaryTable(study);
    summaryChart(study);
  }
  ImGui::End();
}

}  // namespace at::app
