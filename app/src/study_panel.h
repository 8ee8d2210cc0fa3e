// The desktop app's study screens (issue 7): the participant mode of a preference study (blinded
// A/B renderings of each structure, the protocol's items on its 1–5 scale, a comment, progress)
// and the coordinator panel (studies, participants and completion, the export stepped one file
// per frame with a Cancel that removes what it wrote, the Table-2 summary and its chart).
//
// Blinding: while participant mode is active the app draws only the participant window and the
// volume view; that window shows no structure, preset, condition or study names. Every text it
// draws goes through the panel's label helpers, and in scripted mode the labels of each shown
// participant screen (and the ImGui windows that were visible) are printed as a "study_screen" event.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "db/database.h"
#include "db/study_store.h"
#include "render/gl/window_target.h"
#include "render/preset.h"
#include "study_session.h"

namespace at::app {

class StudyPanel {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  // `database`: the app's one connection (it outlives the panel). `events` receives the
  // scripted-mode events.
  StudyPanel(db::Database& database, const render::PresetLibrary& library, EventSink events);
  ~StudyPanel();

  bool participantActive() const { return session_ != nullptr; }
  // What the volume view shows in participant mode: the current trial's structure and the preset
  // of the side on screen (nullopt outside participant mode or after the last trial).
  struct Shown {
    std::string structure;
    render::Preset preset;
    double t = 0.5;
  };
  std::optional<Shown> shown() const;

  // Participant mode: toggles to side 'A' or 'B' (another value: the other side).
  void showSide(char side);

  // The participant window in the app's left panel area, in place of the explore panel.
  void drawParticipant(float width, float height);
  // The coordinator window when open; also steps a running export by one file.
  void drawCoordinator(float x, float y);
  void openCoordinator() { coordinatorOpen_ = true; }

  // A scripted action ("study_start", "study_toggle", "study_rate", "study_comment", "study_next",
  // "study_close", "coordinator_open", "coordinator_export", "coordinator_summary"). Returns
  // nullopt when `what` is not one of them, true when the action is done, false while it runs
  // (an export; with "cancel_after": k it is cancelled once k files are written), or an error
  // naming the problem.
  std::optional<Result<bool>> scriptAction(const std::string& what, const nlohmann::json& action);

 private:
  struct Session;
  Result<db::Database*> database();
  Status startParticipant(const std::string& study, const std::string& participant, const std::string& group);
  Status nextTrial();     // records the current trial and moves on
  void beginTrial();      // resets the per-trial state for the next unrated trial
  void accountView();     // adds the time since the last toggle to the side on screen
  Status selectStudy(const std::string& id);
  Status startExport(const std::string& outDir);
  void stepExport();
  void cancelExport();  // stops a running export and removes the files it wrote
  void refreshStudies();
  void summaryTable();
  void summaryChart();

  // Label helpers for the participant window: draw and remember what was shown.
  void text(const std::string& s);
  void textWrapped(const std::string& s);
  bool button(const std::string& label);
  bool radio(const std::string& label, int* value, int mine);

  db::Database& db_;
  const render::PresetLibrary& library_;
  EventSink events_;

  std::unique_ptr<Session> session_;
  std::vector<std::string> labels_;   // texts drawn in the participant window this frame
  bool announce_ = false;             // print the next drawn participant screen

  // Coordinator
  bool coordinatorOpen_ = false;
  std::vector<quiz::StudyProtocol> studies_;
  int studyIndex_ = -1;
  std::vector<db::StudyCompletion> completion_;
  std::optional<quiz::StudySummary> summary_;
  std::optional<render::gl::ImageTexture> chart_;
  bool chartStale_ = true;
  std::optional<StudyExport> export_;
  std::string exportStatus_;
  bool exportFailed_ = false;
  char outDir_[512] = "study_export";
  char participantId_[64] = "";
  int groupIndex_ = 0;
  std::string coordinatorMessage_;
  bool saveFailed_ = false;
};

}  // namespace at::app
