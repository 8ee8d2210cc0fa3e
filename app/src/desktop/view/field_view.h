// The distance fields of the explore view (no SDL, GL or ImGui here): what the shown structure
// needs, asked of wdt/'s field service; the best field that exists handed to the view (a
// FieldTarget: the GL renderer, or nothing in tests); the locate click's answer-key field.
//
// Policy: a coarse field (about 64 voxels per axis: tens of ms on one core) while hovering, the
// full-resolution field once the mouse has rested kRefineFieldAfterMs on a structure (at once with
// a GPU, or when the coarse grid is the full one). A full-resolution field the user cancelled is not
// asked for again until the hover moves or "Compute it" is pressed. A field computed on the GPU is
// shown from the device before its host copy (for picking) arrives. Until the wanted field is
// complete on screen, the previous one stays; the frame waits for a field only with GPU fields,
// and at most kGpuFieldWaitMs, so that a hover's highlight shows in the frame of the hover
// rather than the next.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/error.h"
#include "view/explore_state.h"
#include "view/frame_scheduler.h"
#include "wdt/field_service.h"

namespace at::app {

inline constexpr double kRefineFieldAfterMs = 400;  // mouse resting this long on a structure → full-res field
inline constexpr int kGpuFieldWaitMs = 6;           // a GPU field at 256³ takes 3–4 ms (H100, bench/RESULTS.md)

// Where fields are shown. show() is called each frame with the wanted field until it returns true
// (complete); a target may take several frames (a host field goes up a few slices per frame).
class FieldTarget {
 public:
  virtual ~FieldTarget() = default;
  // `label`: the field's structure. Errors are reported once and the field is asked again later.
  virtual Result<bool> show(const wdt::FieldService::Cached& field, std::uint16_t label) = 0;
};

class FieldView {
 public:
  using EventSink = std::function<void(nlohmann::json)>;
  using MessageSink = std::function<void(const std::string&)>;
  // A locate answer's weighted distance became known (negative: unknown).
  using ClickGraded = std::function<void(const std::string& clicked, double distanceMm)>;
  // `dataset` (its volume and labels) outlives the view; `state` is the explore state showing it.
  // `notes`: neutral information for the user (fields computed on the CPU), else to `messages`.
  FieldView(const Dataset& dataset, ExploreState& state, EventSink events, MessageSink messages, ClickGraded clickGraded,
            MessageSink notes = {});
  ~FieldView();

  // Each frame: takes finished fields, serves a pending click, asks for what the shown structure
  // needs and hands the best field to `target` (null: no view; fields count as shown when ready).
  // `recorder` receives the upload time.
  void update(FieldTarget* target, FrameRecorder& recorder);

  // The hovered structure changed: the rest timer starts over and a cancelled field may be asked again.
  void hoverChanged();
  // The dataset's labels are edited (the segment editor): `write` changes them while no field
  // computation reads them (wdt::FieldService::updateLabels); fields of the `changed` labels are
  // dropped, and the field on screen, if it is of one of them, is asked for again (it stays on
  // screen until the new one is there).
  void labelsChanged(const std::function<void()>& write, const std::vector<std::uint16_t>& changed);
  // A locate click off its target: graded once the target's answer-key field (wdt/answer_keys.h)
  // is there, through the service (never on this thread).
  void gradeClickDistance(const std::string& clicked, std::uint16_t target, const Vec3& pointMm);
  bool clickPending() const { return pendingClick_.has_value(); }

  // The request of the full-resolution field `label` is shown with under `params` (a preset's WDT
  // parameters), as the view asks for it; the request of `target`'s answer-key field, as a locate
  // click off the target asks for it. Prefetch lists are made of these so that the keys agree.
  static wdt::FieldRequest viewFieldRequest(std::uint16_t label, const WdtParams& params);
  static wdt::FieldRequest answerKeyRequest(std::uint16_t target);
  // Fields the view is expected to need soon (a lesson's coming steps), in the order wanted,
  // computed while the service is otherwise idle (wdt::FieldService::prefetch) [field_prefetched
  // as each arrives]. Kept: the first of each key, at most kPrefetchFields of them and
  // kPrefetchBudgetBytes in all (a field that would pass the budget ends the list), so that the
  // prefetched fields and the view's own (fine and coarse) fit the service's cache together.
  // Replaces the last list; an empty list drops it and cancels a running prefetch. Returns the
  // number of fields kept.
  static constexpr std::size_t kCacheFields = 8;
  static constexpr std::size_t kPrefetchFields = kCacheFields - 2;
  static constexpr std::size_t kPrefetchBudgetBytes = std::size_t(512) << 20;
  std::size_t prefetch(const std::vector<wdt::FieldRequest>& requests);
  bool prefetching() const { return service_->prefetching(); }
  // wdt::FieldService::holdPrefetches: no prefetch starts while the view is still converging.
  void holdPrefetches(bool hold) { service_->holdPrefetches(hold); }
  // The full-resolution field being computed, if any: cancelled, and not asked again (an event
  // "field_cancelled" says how far it got). False when none was running.
  bool cancelFineField();
  // "Compute it": a cancelled full-resolution field may be asked again.
  void allowDeclined() { declinedKey_.clear(); }
  bool declined() const { return !declinedKey_.empty(); }

  // The field the view needs is on screen (or, cancelled, the coarse one); true in bare mode.
  bool settled() const;
  bool busy() const { return service_->busy(); }
  bool uploading() const { return uploading_; }
  // When the field on screen last became final (update() finished showing it); the epoch before any.
  Clock::time_point shownAt() const { return shownAt_; }
  std::optional<wdt::FieldService::Running> running() const { return service_->running(); }
  int cancelledCount() const { return service_->cancelledCount(); }
  const std::string& status() const { return status_; }
  // The host copy of the field on screen, for picking (may lag a GPU field).
  const DistanceField* pickField() const { return field_.get(); }
  // The same, shared: for work that reads it off the UI thread (the distance unit's measure).
  std::shared_ptr<const DistanceField> shownField() const { return field_; }

 private:
  std::optional<wdt::FieldRequest> request(std::uint16_t label, int downsample) const;
  int coarseDownsample() const;
  std::string idOf(std::uint16_t label) const;  // the structure's id, else its label
  void takeFinished();
  bool servePendingClick();  // true while the click still waits for its field

  const Dataset& dataset_;
  ExploreState& state_;
  EventSink events_;
  MessageSink messages_;
  MessageSink notes_;
  ClickGraded clickGraded_;
  std::unique_ptr<wdt::FieldService> service_;
  std::shared_ptr<const DistanceField> field_;
  const void* source_ = nullptr;  // identity of the field on screen; null = none
  std::string key_;
  Clock::time_point shownAt_{};
  std::string lastUploadError_;  // reported once until an upload call succeeds
  bool gpuFields_ = false;
  bool uploading_ = false;
  std::string status_;
  Clock::time_point hoverSince_ = Clock::now();
  std::string declinedKey_;       // a full-resolution field the user cancelled: not asked again
  std::string lastWarning_;       // shown once, not on every field
  bool cpuNotice_ = false;        // told the user that fields run on the CPU
  struct PendingClick {
    std::string clicked;
    Vec3 pointMm{0, 0, 0};
    wdt::FieldRequest keyField;
  };
  std::optional<PendingClick> pendingClick_;
};

}  // namespace at::app
