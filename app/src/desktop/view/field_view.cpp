#include "view/field_view.h"

#include <algorithm>
#include <cstdio>

#include "wdt/answer_keys.h"

namespace at::app {

using wdt::FieldRequest;
using wdt::FieldService;

FieldView::FieldView(const Dataset& dataset, ExploreState& state, EventSink events, MessageSink messages,
                     ClickGraded clickGraded, MessageSink notes)
    : dataset_(dataset),
      state_(state),
      events_(std::move(events)),
      messages_(std::move(messages)),
      notes_(std::move(notes)),
      clickGraded_(std::move(clickGraded)),
      service_(std::make_unique<FieldService>(dataset.volume, dataset.labels, kCacheFields)) {}

FieldView::~FieldView() { service_->cancelAll(); }

int FieldView::coarseDownsample() const {
  const Dims& d = dataset_.volume.dims();
  const int largest = std::max({d.x, d.y, d.z});
  return std::max(1, (largest + 63) / 64);  // about 64 voxels per axis: tens of ms on one core
}

std::optional<FieldRequest> FieldView::request(std::uint16_t label, int downsample) const {
  auto params = state_.fieldParams(label);
  if (!params) return std::nullopt;
  FieldRequest r;
  r.label = label;
  r.params = *params;
  r.params.downsample = downsample;
  r.params.backend = WdtBackend::Auto;
  return r;
}

std::string FieldView::idOf(std::uint16_t label) const {
  const Structure* st = dataset_.findStructureByLabel(label);
  return st ? st->id : std::to_string(label);
}

FieldRequest FieldView::viewFieldRequest(std::uint16_t label, const WdtParams& params) {
  FieldRequest r;
  r.label = label;
  r.params = params;
  r.params.downsample = 1;
  r.params.backend = WdtBackend::Auto;  // as request() asks
  return r;
}

FieldRequest FieldView::answerKeyRequest(std::uint16_t target) {
  FieldRequest r;
  r.label = target;
  r.params = wdt::answerKeyParams();
  return r;
}

std::size_t FieldView::prefetch(const std::vector<FieldRequest>& requests) {
  const Dims& d = dataset_.volume.dims();
  std::vector<FieldRequest> kept;
  std::vector<std::string> keys;
  std::size_t bytes = 0;
  for (const FieldRequest& r : requests) {
    if (kept.size() >= kPrefetchFields) break;
    const std::string key = r.key();
    if (std::find(keys.begin(), keys.end(), key) != keys.end()) continue;
    const std::size_t ds = std::size_t(std::max(1, r.params.downsample));
    const std::size_t fieldBytes = ((std::size_t(d.x) + ds - 1) / ds) * ((std::size_t(d.y) + ds - 1) / ds) *
                                   ((std::size_t(d.z) + ds - 1) / ds) * sizeof(float);
    if (bytes + fieldBytes > kPrefetchBudgetBytes) break;
    bytes += fieldBytes;
    keys.push_back(key);
    kept.push_back(r);
  }
  service_->prefetch(kept);
  return kept.size();
}

void FieldView::hoverChanged() {
  declinedKey_.clear();
  hoverSince_ = Clock::now();
}

void FieldView::labelsChanged(const std::function<void()>& write, const std::vector<std::uint16_t>& changed) {
  service_->updateLabels(write, changed);
  if (std::find(changed.begin(), changed.end(), state_.fieldLabel()) == changed.end()) return;
  source_ = nullptr;  // the field shown is stale: update() shows the new one once it is there
  key_.clear();
}

void FieldView::gradeClickDistance(const std::string& clicked, std::uint16_t target, const Vec3& pointMm) {
  pendingClick_ = PendingClick{clicked, pointMm, answerKeyRequest(target)};
  servePendingClick();
}

bool FieldView::servePendingClick() {
  if (!pendingClick_) return false;
  const FieldService::Cached key = service_->cached(pendingClick_->keyField);
  if (!key.host) {
    service_->request(pendingClick_->keyField);  // a GPU field's host copy follows shortly
    return true;
  }
  const auto distance = wdt::answerKeyDistanceAt(*key.host, dataset_.labels.geometry, pendingClick_->pointMm);
  const PendingClick click = *std::exchange(pendingClick_, std::nullopt);
  clickGraded_(click.clicked, distance.value_or(-1));
  return false;
}

void FieldView::takeFinished() {
  for (wdt::FinishedField& f : service_->takeFinished()) {
    const std::string id = idOf(f.request.label);
    if (!f.field && !f.deviceField) {
      messages_("distance field of " + id + ": " + f.message);
      if (pendingClick_ && pendingClick_->keyField.key() == f.request.key()) {  // graded as "distance unknown"
        const PendingClick click = *std::exchange(pendingClick_, std::nullopt);
        clickGraded_(click.clicked, -1);
      }
      continue;
    }
    if (f.device.find("CPU") == std::string::npos && !f.device.empty()) gpuFields_ = true;
    if (!f.message.empty() && f.message != lastWarning_) messages_(f.message);  // e.g. a CUDA failure
    lastWarning_ = f.message;
    if (!gpuFields_ && !cpuNotice_ && f.message.empty()) {
      cpuNotice_ = true;
      (notes_ ? notes_ : messages_)("No CUDA GPU: distance fields run on the " + f.device +
                                    ", coarse while hovering, full resolution at rest.");
    }
    if (f.prefetched) {  // not on screen yet: no status line
      events_({{"event", "field_prefetched"}, {"structure", id}, {"downsample", f.request.params.downsample},
               {"ms", f.ms}, {"device", f.device}});
      continue;
    }
    char buf[200];
    std::snprintf(buf, sizeof buf, "%s: field 1/%d in %.0f ms on %s", id.c_str(), f.request.params.downsample, f.ms,
                  f.device.c_str());
    status_ = buf;
    events_({{"event", "field"}, {"structure", id}, {"downsample", f.request.params.downsample}, {"ms", f.ms},
             {"device", f.device}});
  }
}

void FieldView::update(FieldTarget* target, FrameRecorder& recorder) {
  takeFinished();
  // Set again below while the field wanted is still going up; every other way out leaves it off,
  // so that the frame loop can go idle.
  uploading_ = false;
  const bool clickWaiting = servePendingClick();  // its field goes first: requests are latest-wins
  if (state_.bare()) return;
  const std::uint16_t label = state_.shownLabel();
  if (!label) return;
  auto fine = request(label, 1);
  auto coarse = request(label, coarseDownsample());
  if (!fine || !coarse) return;
  // A field is ready when its host copy or (computed on the GPU) its device copy exists.
  FieldService::Cached fineCached = service_->cached(*fine);
  bool fineReady = fineCached.ready();
  FieldService::Cached coarseCached = fineReady ? FieldService::Cached{} : service_->cached(*coarse);
  const bool coarseReady = coarseCached.ready();
  const bool resting = msBetween(hoverSince_, Clock::now()) > kRefineFieldAfterMs;
  if (!fineReady && !clickWaiting) {
    if (service_->computing(*fine)) {
      // Already on its way (a lesson step's field prefetched while the student read the step
      // before): taken over as the request rather than cancelled for a coarse one.
      service_->request(*fine);
    } else if (fine->key() == declinedKey_ && (coarseReady || coarseDownsample() == 1)) {
      // the user cancelled this full-resolution field: keep the coarse one
    } else if (gpuFields_ || coarseDownsample() == 1 || (coarseReady && resting)) {
      service_->request(*fine);
      if (gpuFields_) {  // a few ms on the GPU: shown in this frame rather than the next
        fineCached = service_->waitFor(*fine, std::chrono::milliseconds(kGpuFieldWaitMs));
        fineReady = fineCached.ready();
        if (fineReady) coarseCached = {};
      }
    } else if (!coarseReady) {
      service_->request(*coarse);
    }
  }
  const FieldService::Cached& chosen = fineReady ? fineCached : coarseCached;
  const void* source = chosen.device ? static_cast<const void*>(chosen.device.get()) : static_cast<const void*>(chosen.host.get());
  const std::string key = fineReady ? fine->key() : coarse->key();
  if (source && source == source_ && key == key_ && state_.fieldLabel() == label) {
    if (!field_ && chosen.host) field_ = chosen.host;  // the host copy of the field shown arrived
    return;
  }
  if (!source) return;
  if (target) {
    const Clock::time_point start = Clock::now();
    auto complete = target->show(chosen, label);
    recorder.noteUpload(msBetween(start, Clock::now()));
    if (!complete) {
      if (complete.error().message != lastUploadError_) messages_("uploading the field: " + complete.error().message);
      lastUploadError_ = complete.error().message;
      return;
    }
    lastUploadError_.clear();
    uploading_ = !*complete;
    if (!*complete) return;
  }
  field_ = chosen.host;
  source_ = source;
  key_ = key;
  shownAt_ = Clock::now();
  state_.setFieldShown(label, key);
}

bool FieldView::settled() const {
  if (state_.bare() || state_.wholeVolume()) return true;  // no field is needed
  const std::uint16_t label = state_.shownLabel();
  auto fine = request(label, 1);
  if (fine && fine->key() == declinedKey_) {  // the user cancelled it: the coarse field is final
    auto coarse = request(label, coarseDownsample());
    return coarse && state_.fieldLabel() == label && key_ == coarse->key();
  }
  return fine && state_.fieldLabel() == label && key_ == fine->key();
}

bool FieldView::cancelFineField() {
  const auto r = service_->running();
  if (!r || r->request.params.downsample != 1) return false;
  declinedKey_ = r->request.key();
  service_->cancelAll();
  events_({{"event", "field_cancelled"}, {"structure", idOf(r->request.label)}, {"downsample", 1},
           {"passes_done", r->passesDone}, {"passes_planned", r->passesPlanned}, {"elapsed_ms", r->elapsedMs}});
  return true;
}

}  // namespace at::app
