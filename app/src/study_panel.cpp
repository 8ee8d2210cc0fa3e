#include "study_panel.h"

#include <algorithm>
#include <cstdio>
#include <cstring>

#include <imgui.h>
#include <imgui_internal.h>

#include "render/image.h"

namespace at::app {

namespace {

using Clock = std::chrono::steady_clock;
using json = nlohmann::json;

double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

// The visible part of an ImGui label (before "##").
std::string visible(const std::string& label) { return label.substr(0, label.find("##")); }

}  // namespace

struct StudyPanel::Session {
  quiz::StudyProtocol protocol;
  db::StudyParticipant participant;
  std::map<std::string, render::Preset> presets;  // by preset id
  std::optional<std::size_t> trial;               // index into participant.trials; nullopt: finished
  char side = 'A';
  Clock::time_point since = Clock::now(), trialStart = Clock::now();
  double viewMs[2] = {0, 0};
  int toggles = 0;
  std::map<std::string, int> ratings;              // item → rating as shown (0: not yet)
  std::map<std::string, double> responseMs;        // item → ms from the trial's start to its rating
  char comment[1024] = "";
};

StudyPanel::StudyPanel(db::Database& database, const render::PresetLibrary& library, EventSink events)
    : db_(database), library_(library), events_(std::move(events)) {}

StudyPanel::~StudyPanel() = default;

Result<db::Database*> StudyPanel::database() { return &db_; }

// ---------------------------------------------------------------------------------------------
// Participant mode

std::optional<StudyPanel::Shown> StudyPanel::shown() const {
  if (!session_ || !session_->trial) return std::nullopt;
  const db::StudyTrial& trial = session_->participant.trials[*session_->trial];
  const std::string& id = session_->side == 'A' ? trial.presetA : trial.presetB;
  auto it = session_->presets.find(id);
  if (it == session_->presets.end()) return std::nullopt;
  return Shown{trial.structure, it->second, session_->protocol.t};
}

Status StudyPanel::startParticipant(const std::string& study, const std::string& participant, const std::string& group) {
  if (participant.empty()) return fail("study: enter a participant id");
  auto database = this->database();
  if (!database) return tl::unexpected(database.error());
  auto protocol = resolveStudy(**database, study);
  if (!protocol) return tl::unexpected(protocol.error());
  auto presets = loadStudyPresets(library_, *protocol);
  if (!presets) return tl::unexpected(presets.error());
  auto state = db::enrolOrResume(**database, *protocol, participant, group);
  if (!state) return tl::unexpected(state.error());
  session_ = std::make_unique<Session>();
  session_->protocol = std::move(*protocol);
  session_->presets = std::move(*presets);
  session_->participant = std::move(*state);
  beginTrial();
  return {};
}

void StudyPanel::beginTrial() {
  Session& s = *session_;
  s.trial = s.participant.nextTrial(s.protocol.items.size());
  s.side = 'A';
  s.since = s.trialStart = Clock::now();
  s.viewMs[0] = s.viewMs[1] = 0;
  s.toggles = 0;
  s.ratings.clear();
  s.responseMs.clear();
  s.comment[0] = '\0';
  for (const auto& item : s.protocol.items) s.ratings[item.id] = 0;
  labels_.clear();  // the screen of the previous trial is not this one's
  announce_ = true;
}

void StudyPanel::accountView() {
  Session& s = *session_;
  s.viewMs[s.side == 'A' ? 0 : 1] += msSince(s.since);
  s.since = Clock::now();
}

void StudyPanel::showSide(char side) {
  if (!session_ || !session_->trial) return;
  if (side != 'A' && side != 'B') side = session_->side == 'A' ? 'B' : 'A';
  if (side == session_->side) return;
  accountView();
  session_->side = side;
  ++session_->toggles;
  events_({{"event", "study_toggle"}, {"showing", std::string(1, side)}, {"toggles", session_->toggles}});
}

Status StudyPanel::nextTrial() {
  if (!session_ || !session_->trial) return fail("study: no trial is open");
  Session& s = *session_;
  db::StudyTrial& trial = s.participant.trials[*s.trial];
  for (const auto& item : s.protocol.items)
    if (s.ratings[item.id] == 0) return fail("study: rate every question before going on");
  auto database = this->database();
  if (!database) return tl::unexpected(database.error());
  accountView();
  const render::Preset& wdt = s.presets.at(s.protocol.presetFor(trial.structure, 0));
  // Each rating is its own transaction, committed before the next.
  for (const auto& item : s.protocol.items) {
    const db::RatingRecord r = makeRating(s.protocol, wdt, trial.position, item.id, s.ratings[item.id],
                                          s.responseMs.count(item.id) ? s.responseMs[item.id] : msSince(s.trialStart));
    if (auto st = db::recordRating(**database, s.participant, r); !st) return st;
    trial.ratedItems.insert(item.id);
  }
  if (auto st = db::recordTrialViewing(**database, s.participant, trial.position,
                                       s.viewMs[0], s.viewMs[1], s.toggles, s.comment);
      !st)
    return st;
  events_({{"event", "study_recorded"}, {"position", trial.position + 1}, {"view_ms_a", s.viewMs[0]},
           {"view_ms_b", s.viewMs[1]}, {"toggles", s.toggles}});
  beginTrial();
  if (!s.trial) {
    if (auto st = db::markParticipantComplete(**database, s.participant); !st) return st;
    events_({{"event", "study_complete"}, {"trials", s.participant.trials.size()}});
  }
  return {};
}

void StudyPanel::text(const std::string& s) {
  labels_.push_back(s);
  ImGui::TextUnformatted(s.c_str());
}

void StudyPanel::textWrapped(const std::string& s) {
  labels_.push_back(s);
  ImGui::PushTextWrapPos(0);
  ImGui::TextUnformatted(s.c_str());
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

void StudyPanel::drawParticipant(float width, float height) {
  if (!session_) return;
  if (announce_ && !labels_.empty()) {
    // The screen drawn last frame is now on screen: print its labels and the visible windows.
    json windows = json::array();
    for (ImGuiWindow* w : ImGui::GetCurrentContext()->Windows)
      if (w->WasActive && !(w->Flags & ImGuiWindowFlags_ChildWindow) && std::strncmp(w->Name, "Debug##", 7) != 0)
        windows.push_back(visible(w->Name));  // top-level windows, tooltips and popups included
    events_({{"event", "study_screen"}, {"labels", labels_}, {"windows", windows}});
    announce_ = false;
  }
  labels_.clear();
  Session& s = *session_;
  ImGui::SetNextWindowPos(ImVec2(0, 0));
  ImGui::SetNextWindowSize(ImVec2(width, height));
  ImGui::Begin("Preference study", nullptr,
               ImGuiWindowFlags_NoMove | ImGuiWindowFlags_NoResize | ImGuiWindowFlags_NoCollapse |
                   ImGuiWindowFlags_NoTitleBar);
  if (!s.trial) {
    text("Thank you!");
    textWrapped("All " + std::to_string(s.participant.trials.size()) + " structures are rated. Your answers are saved.");
    if (button("Close")) {
      session_.reset();
      ImGui::End();
      return;
    }
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
    if (button(std::string("View ") + side)) showSide(side);
    if (on) ImGui::PopStyleColor();
  }
  text(std::string("Now showing: view ") + s.side);
  ImGui::Separator();
  // The protocol's anchors once, then each item on the scale.
  for (const auto& [value, anchor] : s.protocol.scale.anchors) text(std::to_string(value) + " = " + anchor);
  ImGui::Separator();
  for (const auto& item : s.protocol.items) {
    textWrapped(item.wording);
    int& rating = s.ratings[item.id];
    for (int v = s.protocol.scale.min; v <= s.protocol.scale.max; ++v) {
      if (v > s.protocol.scale.min) ImGui::SameLine();
      if (radio(std::to_string(v) + "##" + item.id, &rating, v)) s.responseMs[item.id] = msSince(s.trialStart);
    }
    ImGui::Spacing();
  }
  text("Comment (optional)");
  ImGui::InputTextMultiline("##comment", s.comment, sizeof s.comment, ImVec2(-1, ImGui::GetTextLineHeight() * 3));
  bool allRated = true;
  for (const auto& item : s.protocol.items) allRated = allRated && s.ratings[item.id] != 0;
  if (!allRated) ImGui::BeginDisabled();
  const bool next = button("Next");
  if (!allRated) ImGui::EndDisabled();
  if (next) {
    // The detailed error may name the study: it goes to the log, the participant sees a plain note.
    if (auto st = nextTrial(); !st) {
      std::fprintf(stderr, "anatomy-tutor: %s\n", st.error().message.c_str());
      saveFailed_ = true;
    } else {
      saveFailed_ = false;
    }
  }
  if (saveFailed_) textWrapped("Your answers could not be saved. Please tell the study coordinator.");
  // Leaves participant mode; answers up to the last Next are saved, and starting the same
  // participant again resumes at the first unrated structure.
  ImGui::SameLine(ImGui::GetWindowWidth() - 80);
  if (button("Pause")) {
    session_.reset();
    saveFailed_ = false;
  }
  ImGui::End();
}

// ---------------------------------------------------------------------------------------------
// Coordinator panel

void StudyPanel::refreshStudies() {
  coordinatorMessage_.clear();
  auto database = this->database();
  if (!database) {
    coordinatorMessage_ = database.error().message;
    return;
  }
  // Shipped studies are registered on first sight, as `study run` does.
  for (const std::string& id : shippedStudyIds())
    if (auto p = resolveStudy(**database, id); !p) coordinatorMessage_ = p.error().message;
  auto studies = db::listStudies(**database);
  if (!studies) {
    coordinatorMessage_ = studies.error().message;
    return;
  }
  const std::string current =
      studyIndex_ >= 0 && studyIndex_ < int(studies_.size()) ? studies_[std::size_t(studyIndex_)].id : "";
  studies_ = std::move(*studies);
  studyIndex_ = studies_.empty() ? -1 : 0;
  for (int i = 0; i < int(studies_.size()); ++i)
    if (studies_[std::size_t(i)].id == current) studyIndex_ = i;
  if (studyIndex_ >= 0)
    if (auto st = selectStudy(studies_[std::size_t(studyIndex_)].id); !st) coordinatorMessage_ = st.error().message;
}

Status StudyPanel::selectStudy(const std::string& id) {
  auto database = this->database();
  if (!database) return tl::unexpected(database.error());
  auto it = std::find_if(studies_.begin(), studies_.end(), [&](const auto& p) { return p.id == id; });
  if (it == studies_.end()) {
    auto p = resolveStudy(**database, id);
    if (!p) return tl::unexpected(p.error());
    studies_.push_back(*p);
    it = std::prev(studies_.end());
  }
  studyIndex_ = int(it - studies_.begin());
  auto completion = db::studyCompletion(**database, id);
  if (!completion) return tl::unexpected(completion.error());
  completion_ = std::move(*completion);
  auto rows = db::studyResponseRows(**database, *it);
  if (!rows) return tl::unexpected(rows.error());
  summary_ = quiz::summariseStudy(*it, *rows);
  chartStale_ = true;
  groupIndex_ = std::clamp(groupIndex_, 0, std::max(0, int(it->groups.size()) - 1));
  return {};
}

Status StudyPanel::startExport(const std::string& outDir) {
  if (studyIndex_ < 0) return fail("coordinator: no study is selected");
  auto database = this->database();
  if (!database) return tl::unexpected(database.error());
  auto prepared = StudyExport::prepare(**database, studies_[std::size_t(studyIndex_)], outDir);
  if (!prepared) return tl::unexpected(prepared.error());
  export_ = std::move(*prepared);
  exportFailed_ = false;
  char progress[64];
  std::snprintf(progress, sizeof progress, "[0/%zu] preparing", export_->fileCount());
  exportStatus_ = progress;
  return {};
}

// One file per frame, so the panel redraws between files.
void StudyPanel::stepExport() {
  if (!export_ || export_->done()) return;
  const std::string name = export_->nextName();
  const std::size_t k = export_->written() + 1, n = export_->fileCount();
  if (auto st = export_->writeNext(); !st) {
    exportStatus_ = st.error().message;
    exportFailed_ = true;
    events_({{"event", "export_failed"}, {"message", exportStatus_}});
    export_.reset();
    return;
  }
  char progress[64];
  std::snprintf(progress, sizeof progress, "[%zu/%zu] ", k, n);
  exportStatus_ = progress + name;
  events_({{"event", "export_progress"}, {"k", k}, {"n", n}, {"file", name}});
  if (export_->done()) events_({{"event", "export_done"}, {"files", n}, {"rows", export_->rowCount()}});
}

void StudyPanel::cancelExport() {
  if (!export_ || export_->done()) return;
  const std::size_t k = export_->written(), n = export_->fileCount();
  const Status removed = export_->discardWritten();
  export_.reset();
  exportFailed_ = !removed;
  exportStatus_ = removed ? "Export cancelled after " + std::to_string(k) + " of " + std::to_string(n) +
                                " files; those were removed."
                          : "Export cancelled; " + removed.error().message;
  events_({{"event", "export_cancelled"}, {"written", k}, {"n", n}, {"removed", bool(removed)}});
}

void StudyPanel::summaryTable() {
  if (!summary_ || summary_->items.empty()) return;
  const quiz::StudySummary& sum = *summary_;
  const int columns = 1 + int(sum.columns.size());
  if (!ImGui::BeginTable("table2", columns,
                         ImGuiTableFlags_Borders | ImGuiTableFlags_RowBg | ImGuiTableFlags_SizingFixedFit))
    return;
  ImGui::TableSetupColumn("item");
  for (const std::string& c : sum.columns) ImGui::TableSetupColumn(c.c_str());
  ImGui::TableHeadersRow();
  for (std::size_t i = 0; i < sum.items.size(); ++i) {
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    ImGui::TextUnformatted(sum.items[i].c_str());
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

void StudyPanel::summaryChart() {
  if (!summary_ || studyIndex_ < 0) return;
  if (chartStale_) {
    chartStale_ = false;
    const RgbImage chart = quiz::renderSummaryChart(studies_[std::size_t(studyIndex_)], *summary_);
    render::RgbaImage rgba(chart.width, chart.height);
    for (std::size_t i = 0; i < std::size_t(chart.width) * std::size_t(chart.height); ++i) {
      for (std::size_t c = 0; c < 3; ++c) rgba.rgba[i * 4 + c] = chart.rgb[i * 3 + c];
      rgba.rgba[i * 4 + 3] = 255;
    }
    if (!chart_) {
      auto texture = render::gl::ImageTexture::create();
      if (!texture) {
        coordinatorMessage_ = texture.error().message;
        return;
      }
      chart_ = std::move(*texture);
    }
    if (auto st = chart_->upload(rgba); !st) coordinatorMessage_ = st.error().message;
  }
  if (!chart_ || !chart_->handle() || chart_->width() <= 0) return;
  const float w = std::min(ImGui::GetContentRegionAvail().x, float(chart_->width()));
  ImGui::Image(reinterpret_cast<ImTextureID>(chart_->handle()),
               ImVec2(w, w * float(chart_->height()) / float(chart_->width())));
}

void StudyPanel::drawCoordinator(float x, float y) {
  stepExport();
  if (!coordinatorOpen_ || session_) return;
  if (studies_.empty() && coordinatorMessage_.empty()) refreshStudies();
  ImGui::SetNextWindowPos(ImVec2(x, y), ImGuiCond_Appearing);
  ImGui::SetNextWindowSize(ImVec2(760, 620), ImGuiCond_Appearing);
  if (!ImGui::Begin("Studies (coordinator)", &coordinatorOpen_)) {
    ImGui::End();
    return;
  }
  if (ImGui::Button("Refresh")) refreshStudies();
  ImGui::SameLine();
  const std::string current = studyIndex_ >= 0 ? studies_[std::size_t(studyIndex_)].id : "(no study)";
  ImGui::SetNextItemWidth(320);
  if (ImGui::BeginCombo("study", current.c_str())) {
    for (int i = 0; i < int(studies_.size()); ++i) {
      const std::string id = studies_[std::size_t(i)].id;
      if (ImGui::Selectable(id.c_str(), i == studyIndex_))
        if (auto st = selectStudy(id); !st) coordinatorMessage_ = st.error().message;
    }
    ImGui::EndCombo();
  }
  if (!coordinatorMessage_.empty()) ImGui::TextColored(ImVec4(1, 0.5f, 0.4f, 1), "%s", coordinatorMessage_.c_str());
  if (studyIndex_ < 0) {
    ImGui::End();
    return;
  }
  const quiz::StudyProtocol& p = studies_[std::size_t(studyIndex_)];
  ImGui::PushTextWrapPos(0);
  ImGui::TextDisabled("%s", p.title.c_str());
  ImGui::PopTextWrapPos();
  ImGui::Text("%zu structures, %zu items, dataset %s", p.structures.size(), p.items.size(), p.dataset.c_str());

  if (ImGui::CollapsingHeader("Participants", ImGuiTreeNodeFlags_DefaultOpen)) {
    if (completion_.empty()) ImGui::TextDisabled("nobody enrolled yet");
    for (const db::StudyCompletion& c : completion_)
      ImGui::Text("%-16s %-12s %3d/%d ratings  %s", c.participantId.c_str(), c.group.c_str(), c.ratingsGiven,
                  c.ratingsExpected, c.complete ? "complete" : "in progress");
    ImGui::SetNextItemWidth(160);
    ImGui::InputTextWithHint("##pid", "participant id", participantId_, sizeof participantId_);
    if (!p.groups.empty()) {
      groupIndex_ = std::clamp(groupIndex_, 0, int(p.groups.size()) - 1);
      ImGui::SameLine();
      ImGui::SetNextItemWidth(140);
      if (ImGui::BeginCombo("##group", p.groups[std::size_t(groupIndex_)].c_str())) {
        for (int i = 0; i < int(p.groups.size()); ++i)
          if (ImGui::Selectable(p.groups[std::size_t(i)].c_str(), i == groupIndex_)) groupIndex_ = i;
        ImGui::EndCombo();
      }
      ImGui::SameLine();
      if (ImGui::Button("Start participant session")) {
        const std::string id = p.id, group = p.groups[std::size_t(groupIndex_)];
        if (auto st = startParticipant(id, participantId_, group); !st) coordinatorMessage_ = st.error().message;
      }
    }
  }
  if (ImGui::CollapsingHeader("Export", ImGuiTreeNodeFlags_DefaultOpen)) {
    ImGui::SetNextItemWidth(360);
    ImGui::InputText("folder", outDir_, sizeof outDir_);
    ImGui::SameLine();
    const bool running = export_ && !export_->done();
    if (running) ImGui::BeginDisabled();
    if (ImGui::Button("Export")) {
      if (auto st = startExport(outDir_); !st) {
        exportStatus_ = st.error().message;
        exportFailed_ = true;
      }
    }
    if (running) ImGui::EndDisabled();
    if (export_) {
      ImGui::ProgressBar(float(export_->written()) / float(std::max<std::size_t>(1, export_->fileCount())),
                         ImVec2(running ? -80 : -1, 0), exportStatus_.c_str());
      if (running) {
        ImGui::SameLine();
        if (ImGui::Button("Cancel##export")) cancelExport();
      }
    } else if (!exportStatus_.empty()) {
      ImGui::TextColored(exportFailed_ ? ImVec4(1, 0.5f, 0.4f, 1) : ImVec4(1, 1, 1, 1), "%s", exportStatus_.c_str());
    }
  }
  if (ImGui::CollapsingHeader("Summary (Table 2: 1 = prefer WDT ... 5 = prefer bare)", ImGuiTreeNodeFlags_DefaultOpen)) {
    summaryTable();
    summaryChart();
  }
  ImGui::End();
}

// ---------------------------------------------------------------------------------------------
// Scripted actions

std::optional<Result<bool>> StudyPanel::scriptAction(const std::string& what, const json& a) {
  using R = Result<bool>;
  const auto status = [](Status st) -> R {
    if (!st) return tl::unexpected(st.error());
    return true;
  };
  if (what == "study_start")
    return status(startParticipant(a.at("study").get<std::string>(), a.at("participant").get<std::string>(),
                                   a.at("group").get<std::string>()));
  if (what.rfind("study_", 0) == 0 && !session_) return R(fail("ui script: " + what + " needs study_start first"));
  if (what == "study_toggle") {
    const std::string side = a.value("side", "");
    showSide(side.empty() ? '?' : side[0]);
    return R(true);
  }
  if (what == "study_rate") {
    if (!session_->trial) return R(fail("ui script: study_rate after the last trial"));
    const std::string item = a.at("item");
    const int rating = a.at("rating");
    if (!session_->ratings.count(item)) return R(fail("ui script: the study has no item '" + item + "'"));
    if (rating < session_->protocol.scale.min || rating > session_->protocol.scale.max)
      return R(fail("ui script: rating " + std::to_string(rating) + " is off the scale"));
    session_->ratings[item] = rating;
    session_->responseMs[item] = msSince(session_->trialStart);
    return R(true);
  }
  if (what == "study_comment") {
    const std::string text = a.at("text");
    std::snprintf(session_->comment, sizeof session_->comment, "%s", text.c_str());
    return R(true);
  }
  if (what == "study_next") return status(nextTrial());
  if (what == "study_close") {
    session_.reset();
    return R(true);
  }
  if (what == "coordinator_open") {
    coordinatorOpen_ = true;
    refreshStudies();
    if (a.contains("study"))
      if (auto st = selectStudy(a.at("study").get<std::string>()); !st) return R(tl::unexpected(st.error()));
    return R(true);
  }
  if (what == "coordinator_export") {
    // Started on the first call; done once the last file is written (one file per frame).
    if (!export_) {
      if (exportFailed_) return R(fail(exportStatus_));
      if (a.contains("study")) {
        if (auto st = selectStudy(a.at("study").get<std::string>()); !st) return R(tl::unexpected(st.error()));
      } else if (studyIndex_ < 0) {
        refreshStudies();
      }
      if (auto st = startExport(a.at("out").get<std::string>()); !st) return R(tl::unexpected(st.error()));
      return R(false);
    }
    // "cancel_after": k presses Cancel once k files are written (one file per frame: deterministic).
    if (a.contains("cancel_after") && !export_->done() && export_->written() >= a.at("cancel_after").get<std::size_t>()) {
      cancelExport();
      return R(true);
    }
    if (!export_->done()) return R(false);
    export_.reset();
    return R(true);
  }
  if (what == "coordinator_summary") {
    if (a.contains("study"))
      if (auto st = selectStudy(a.at("study").get<std::string>()); !st) return R(tl::unexpected(st.error()));
    if (!summary_) return R(fail("ui script: coordinator_summary: no study is selected"));
    json cells = json::array();
    for (std::size_t i = 0; i < summary_->items.size(); ++i)
      for (std::size_t c = 0; c < summary_->columns.size(); ++c) {
        const auto& cell = summary_->at(i, c);
        cells.push_back({{"item", cell.item}, {"group", cell.group}, {"n", cell.stats.n}, {"mean", cell.stats.mean},
                         {"sd", cell.stats.sd}, {"p", cell.stats.pValue}, {"preferred", cell.preferred}});
      }
    json completion = json::array();
    for (const auto& c : completion_)
      completion.push_back({{"participant", c.participantId}, {"group", c.group}, {"given", c.ratingsGiven},
                            {"expected", c.ratingsExpected}, {"complete", c.complete}});
    events_({{"event", "study_summary"}, {"cells", cells}, {"completion", completion}});
    return R(true);
  }
  return std::nullopt;
}

}  // namespace at::app
