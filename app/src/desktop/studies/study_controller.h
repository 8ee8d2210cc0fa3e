// The desktop's preference studies without drawing (the study panels draw it; the UI script drives
// the same commands): the participant mode of a study (blinded A/B renderings of each structure,
// the protocol's items on its 1–5 scale, a comment, viewing times and toggles; every rating
// committed when the participant goes on) and the coordinator's side (studies, participants and
// completion, the export written one file per frame with a Cancel that removes what it wrote, the
// Table-2 summary and its chart).
//
// Blinding: shown() is all the view learns of a trial (a structure and a preset); the participant
// window draws only what the panel's label helpers record.
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "db/study_store.h"
#include "render/preset.h"
#include "study_session.h"
#include "volume/png_image.h"

namespace at::db {
class Database;
}

namespace at::app {

class StudyController {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  // `database` and `library` outlive the controller.
  // `levels`: the shown dataset's intensity levels, for the presets a study does not have written.
  StudyController(db::Database& database, const render::PresetLibrary& library, EventSink events,
                  StudyLevels levels = {});
  ~StudyController();

  // --- Participant mode -----------------------------------------------------------------------
  struct Participant {
    quiz::StudyProtocol protocol;
    db::StudyParticipant participant;
    std::map<std::string, render::Preset> presets;  // by preset id
    std::optional<std::size_t> trial;               // index into participant.trials; nullopt: finished
    char side = 'A';
    std::chrono::steady_clock::time_point since, trialStart;
    double viewMs[2] = {0, 0};
    int toggles = 0;
    std::map<std::string, int> ratings;              // item → rating as shown (0: not yet)
    std::map<std::string, double> responseMs;        // item → ms from the trial's start to its rating
    std::string comment;
    bool saveFailed = false;                         // the last Next could not be saved
    // The side on screen reached the full quality level (since it was last shown), and how long
    // that took; reset when a trial begins or the side changes.
    bool sideAtFull = false;
    std::optional<double> sideSettleMs;
    std::map<std::string, db::RatingRecord> quality;  // item → the quality on screen when rated
  };
  bool participantActive() const { return participant_ != nullptr; }
  Participant* participant() { return participant_.get(); }
  // What the volume view shows: the current trial's structure and the preset of the side on
  // screen (nullopt outside participant mode or after the last trial).
  struct Shown {
    std::string structure;
    render::Preset preset;
    double t = 0.5;
  };
  std::optional<Shown> shown() const;
  // A new trial began since the last call (its participant window is yet to be announced).
  bool takeNewScreen() { return std::exchange(newScreen_, false); }
  // The participant window's labels as drawn ("study_screen"), for the scripted-mode log: the
  // screen of the current trial is now on display.
  void announce(nlohmann::json screen) {
    screenPending_ = false;
    events_(std::move(screen));
  }
  // The current trial's participant screen (or the closing one) has not been announced yet: a
  // window that draws the panels is still to show it. The UI script waits on this so that its
  // next action acts on the screen the last one caused.
  bool screenPending() const { return participant_ && screenPending_; }

  // What the volume view has on screen, each frame (DesktopModel): the structure and preset id of
  // the image shown and its mode (a report for another than the current side's is an image not yet
  // replaced, or a field mode still drawn bare for want of its field),
  // its quality level (fullLevel: the full level; -1: an image of an older view), the full
  // level's resolution as a share of the view, and the ms from the view's last change to the full
  // level (FrameScheduler::settledAfterMs). Without calls (no view draws: headless) the quality
  // is not known and ratings are taken as they come, with no quality recorded.
  struct ViewQuality {
    std::string structure, presetId;
    render::RenderMode mode = render::RenderMode::Wdt;  // bare while a field mode's field is not on screen yet
    int level = -1;
    int fullLevel = 0;
    double scale = 1;
    std::optional<double> settledMs;
  };
  void noteViewQuality(const ViewQuality& quality);
  // A rating may be given now: no view reports quality, or the side on screen is at full quality
  // (stimuli are rated only once shown at full quality).
  bool readyToRate() const;

  Status startParticipant(const std::string& study, const std::string& participant, const std::string& group);
  void showSide(char side);             // 'A' or 'B' (another value: the other side) [study_toggle]
  Status rate(const std::string& item, int rating);
  void setComment(std::string comment);
  bool allRated() const;
  Status nextTrial();                   // records the trial's ratings and viewing [study_recorded, study_complete]
  void closeParticipant();              // pause or close: answers up to the last Next are saved

  // --- Coordinator ----------------------------------------------------------------------------
  bool coordinatorOpen = false;
  void refreshStudies();                // shipped studies registered on first sight
  Status selectStudy(const std::string& id);
  const std::vector<quiz::StudyProtocol>& studies() const { return studies_; }
  const quiz::StudyProtocol* selectedStudy() const;
  const std::vector<db::StudyCompletion>& completion() const { return completion_; }
  const std::optional<quiz::StudySummary>& summary() const { return summary_; }
  // The Table-2 chart of the selected study (its SVG rasterised, as the export's summary.png);
  // its revision changes when it does. Null when there is none or it could not be drawn
  // (chartError() says why).
  const RgbImage* chart();
  const std::string& chartError() const { return chartError_; }
  std::uint64_t chartRevision() const { return chartRevision_; }
  const std::string& message() const { return message_; }

  Status startExport(const std::string& outDir);
  void stepExport();                    // one file per frame [export_progress, export_done, export_failed]
  void cancelExport();                  // removes what it wrote [export_cancelled]
  const StudyExport* runningExport() const { return export_ ? &*export_ : nullptr; }
  void clearExport() { export_.reset(); }
  bool exportFailed() const { return exportFailed_; }
  const std::string& exportStatus() const { return exportStatus_; }
  // Summary cells and completion as a "study_summary" event.
  nlohmann::json summaryEvent() const;

 private:
  void beginTrial();      // resets the per-trial state for the next unrated trial
  void accountView();     // adds the time since the last toggle to the side on screen

  db::Database& database_;
  const render::PresetLibrary& library_;
  StudyLevels levels_;
  EventSink events_;
  std::unique_ptr<Participant> participant_;
  std::optional<ViewQuality> viewQuality_;  // the latest from the view; nullopt: no view reports
  bool newScreen_ = false;      // a new screen the panel has not begun to draw
  bool screenPending_ = false;  // a new screen not yet announced

  std::vector<quiz::StudyProtocol> studies_;
  int studyIndex_ = -1;
  std::vector<db::StudyCompletion> completion_;
  std::optional<quiz::StudySummary> summary_;
  std::optional<RgbImage> chart_;
  std::string chartError_;
  std::uint64_t chartRevision_ = 0;
  std::optional<StudyExport> export_;
  std::string exportStatus_;
  bool exportFailed_ = false;
  std::string message_;
};

}  // namespace at::app
