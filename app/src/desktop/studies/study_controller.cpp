// [SECTIONS] participant mode · coordinator
#include "studies/study_controller.h"

#include <algorithm>
#include <cstdio>

#include "db/connection.h"
#include "quiz/study_report.h"

namespace at::app {

namespace {
using json = nlohmann::json;
using SteadyClock = std::chrono::steady_clock;
double msSince(SteadyClock::time_point t) { return std::chrono::duration<double, std::milli>(SteadyClock::now() - t).count(); }
}  // namespace

StudyController::StudyController(db::Database& database, const render::PresetLibrary& library, EventSink events,
                                 StudyLevels levels)
    : database_(database), library_(library), levels_(std::move(levels)), events_(std::move(events)) {}

StudyController::~StudyController() = default;

// ---------------------------------------------------------------------------------------------
// Participant mode

std::optional<StudyController::Shown> StudyController::shown() const {
  if (!participant_ || !participant_->trial) return std::nullopt;
  const db::StudyTrial& trial = participant_->participant.trials[*participant_->trial];
  const std::string& id = participant_->side == 'A' ? trial.presetA : trial.presetB;
  auto it = participant_->presets.find(id);
  if (it == participant_->presets.end()) return std::nullopt;
  return Shown{trial.structure, it->second, participant_->protocol.t};
}

Status StudyController::startParticipant(const std::string& study, const std::string& participant, const std::string& group) {
  if (participant.empty()) return fail("study: enter a participant id");
  auto protocol = resolveStudy(database_, study);
  if (!protocol) return tl::unexpected(protocol.error());
  auto presets = loadStudyPresets(library_, *protocol, levels_);
  if (!presets) return tl::unexpected(presets.error());
  auto state = db::enrolOrResume(database_, *protocol, participant, group);
  if (!state) return tl::unexpected(state.error());
  participant_ = std::make_unique<Participant>();
  participant_->protocol = std::move(*protocol);
  participant_->presets = std::move(*presets);
  participant_->participant = std::move(*state);
  beginTrial();
  return {};
}

void StudyController::beginTrial() {
  Participant& s = *participant_;
  s.trial = s.participant.nextTrial(s.protocol.items.size());
  s.side = 'A';
  s.since = s.trialStart = SteadyClock::now();
  s.viewMs[0] = s.viewMs[1] = 0;
  s.toggles = 0;
  s.ratings.clear();
  s.responseMs.clear();
  s.comment.clear();
  s.quality.clear();
  s.sideAtFull = false;
  s.sideSettleMs.reset();
  for (const auto& item : s.protocol.items) s.ratings[item.id] = 0;
  newScreen_ = screenPending_ = true;
}

void StudyController::accountView() {
  Participant& s = *participant_;
  s.viewMs[s.side == 'A' ? 0 : 1] += msSince(s.since);
  s.since = SteadyClock::now();
}

void StudyController::showSide(char side) {
  if (!participant_ || !participant_->trial) return;
  if (side != 'A' && side != 'B') side = participant_->side == 'A' ? 'B' : 'A';
  if (side == participant_->side) return;
  accountView();
  participant_->side = side;
  participant_->sideAtFull = false;  // the other side's image is still to converge
  participant_->sideSettleMs.reset();
  ++participant_->toggles;
  events_({{"event", "study_toggle"}, {"showing", std::string(1, side)}, {"toggles", participant_->toggles}});
}

void StudyController::noteViewQuality(const ViewQuality& quality) {
  viewQuality_ = quality;
  const auto now = shown();
  if (!now || now->structure != quality.structure || now->preset.id.value_or("") != quality.presetId ||
      now->preset.mode != quality.mode) {
    viewQuality_->level = -1;  // the image on screen is not yet the current side's
    return;
  }
  Participant& s = *participant_;
  if (quality.level >= quality.fullLevel && !s.sideAtFull) {
    s.sideAtFull = true;
    // The scheduler counts from the view's last change, which is at or after the side was shown.
    s.sideSettleMs = quality.settledMs;
  }
}

bool StudyController::readyToRate() const {
  return !viewQuality_ || (participant_ && participant_->sideAtFull);
}

Status StudyController::rate(const std::string& item, int rating) {
  if (!participant_ || !participant_->trial) return fail("study: no trial is open");
  Participant& s = *participant_;
  if (!s.ratings.count(item)) return fail("study: the study has no item '" + item + "'");
  if (rating < s.protocol.scale.min || rating > s.protocol.scale.max)
    return fail("study: rating " + std::to_string(rating) + " is off the scale");
  if (!readyToRate())
    return fail(ErrorKind::Unavailable, "study: wait until view " + std::string(1, s.side) +
                                            " is drawn at full quality before rating (level " +
                                            std::to_string(viewQuality_->level) + " of " +
                                            std::to_string(viewQuality_->fullLevel) + " on screen)");
  s.ratings[item] = rating;
  s.responseMs[item] = msSince(s.trialStart);
  db::RatingRecord& q = s.quality[item];
  q = {};
  if (viewQuality_) {
    q.qualityLevel = viewQuality_->level;  // as on screen now (lower if the participant moves the view)
    q.qualityFullLevel = viewQuality_->fullLevel;
    q.qualityScale = viewQuality_->scale;
    q.settleMs = s.sideSettleMs;
  }
  return {};
}

void StudyController::setComment(std::string comment) {
  if (participant_) participant_->comment = std::move(comment);
}

bool StudyController::allRated() const {
  if (!participant_) return false;
  for (const auto& item : participant_->protocol.items)
    if (participant_->ratings.at(item.id) == 0) return false;
  return true;
}

Status StudyController::nextTrial() {
  if (!participant_ || !participant_->trial) return fail("study: no trial is open");
  Participant& s = *participant_;
  db::StudyTrial& trial = s.participant.trials[*s.trial];
  if (!allRated()) return fail("study: rate every question before going on");
  accountView();
  const render::Preset& wdt = s.presets.at(s.protocol.presetFor(trial.structure, 0));
  // Each rating is its own transaction, committed before the next.
  for (const auto& item : s.protocol.items) {
    db::RatingRecord r = makeRating(s.protocol, wdt, trial.position, item.id, s.ratings[item.id],
                                    s.responseMs.count(item.id) ? s.responseMs[item.id] : msSince(s.trialStart));
    if (auto q = s.quality.find(item.id); q != s.quality.end()) {
      r.qualityLevel = q->second.qualityLevel;
      r.qualityFullLevel = q->second.qualityFullLevel;
      r.qualityScale = q->second.qualityScale;
      r.settleMs = q->second.settleMs;
    }
    if (auto st = db::recordRating(database_, s.participant, r); !st) return st;
    trial.ratedItems.insert(item.id);
  }
  if (auto st = db::recordTrialViewing(database_, s.participant, trial.position, s.viewMs[0], s.viewMs[1], s.toggles, s.comment);
      !st)
    return st;
  events_({{"event", "study_recorded"}, {"position", trial.position + 1}, {"view_ms_a", s.viewMs[0]},
           {"view_ms_b", s.viewMs[1]}, {"toggles", s.toggles}});
  beginTrial();
  if (!s.trial) {
    if (auto st = db::markParticipantComplete(database_, s.participant); !st) return st;
    events_({{"event", "study_complete"}, {"trials", s.participant.trials.size()}});
  }
  return {};
}

void StudyController::closeParticipant() { participant_.reset(); }

// ---------------------------------------------------------------------------------------------
// Coordinator

const quiz::StudyProtocol* StudyController::selectedStudy() const {
  return studyIndex_ >= 0 && studyIndex_ < int(studies_.size()) ? &studies_[std::size_t(studyIndex_)] : nullptr;
}

void StudyController::refreshStudies() {
  message_.clear();
  // Shipped studies are registered on first sight, as `study run` does.
  for (const std::string& id : shippedStudyIds())
    if (auto p = resolveStudy(database_, id); !p) message_ = p.error().message;
  auto studies = db::listStudies(database_);
  if (!studies) {
    message_ = studies.error().message;
    return;
  }
  const std::string current = selectedStudy() ? selectedStudy()->id : "";
  studies_ = std::move(*studies);
  studyIndex_ = studies_.empty() ? -1 : 0;
  for (int i = 0; i < int(studies_.size()); ++i)
    if (studies_[std::size_t(i)].id == current) studyIndex_ = i;
  if (studyIndex_ >= 0)
    if (auto st = selectStudy(studies_[std::size_t(studyIndex_)].id); !st) message_ = st.error().message;
}

Status StudyController::selectStudy(const std::string& id) {
  auto it = std::find_if(studies_.begin(), studies_.end(), [&](const auto& p) { return p.id == id; });
  if (it == studies_.end()) {
    auto p = resolveStudy(database_, id);
    if (!p) return tl::unexpected(p.error());
    studies_.push_back(*p);
    it = std::prev(studies_.end());
  }
  studyIndex_ = int(it - studies_.begin());
  auto completion = db::studyCompletion(database_, id);
  if (!completion) return tl::unexpected(completion.error());
  completion_ = std::move(*completion);
  auto rows = db::studyResponseRows(database_, *it);
  if (!rows) return tl::unexpected(rows.error());
  summary_ = quiz::summariseStudy(*it, *rows);
  chart_.reset();
  chartError_.clear();
  ++chartRevision_;
  return {};
}

const RgbImage* StudyController::chart() {
  if (!summary_ || !selectedStudy()) return nullptr;
  if (!chart_ && chartError_.empty()) {
    auto rasterised = summaryChart(*selectedStudy(), *summary_);
    if (!rasterised) {
      chartError_ = rasterised.error().message;
      return nullptr;
    }
    chart_ = std::move(*rasterised);
  }
  return chart_ ? &*chart_ : nullptr;
}

Status StudyController::startExport(const std::string& outDir) {
  if (!selectedStudy()) return fail("coordinator: no study is selected");
  auto prepared = StudyExport::prepare(database_, *selectedStudy(), outDir);
  if (!prepared) {
    exportStatus_ = prepared.error().message;
    exportFailed_ = true;
    return tl::unexpected(prepared.error());
  }
  export_ = std::move(*prepared);
  exportFailed_ = false;
  char progress[64];
  std::snprintf(progress, sizeof progress, "[0/%zu] preparing", export_->fileCount());
  exportStatus_ = progress;
  return {};
}

void StudyController::stepExport() {
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

void StudyController::cancelExport() {
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

json StudyController::summaryEvent() const {
  json cells = json::array();
  if (summary_)
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
  return {{"event", "study_summary"}, {"cells", cells}, {"completion", completion}};
}

}  // namespace at::app
