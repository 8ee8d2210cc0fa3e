#include "wdt/field_service.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "cpu_fallback.h"
#include "volume/mask.h"

#if defined(AT_HAVE_CUDA)
#include "cuda/wdt_cuda.h"
#include "wdt/huge_pages.h"
#endif

namespace at::wdt {

namespace {
double msSince(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t).count();
}
}  // namespace

#if defined(AT_HAVE_CUDA)
struct FieldService::DeviceState {
  std::optional<cuda::DeviceVolume> volume;
};
#else
struct FieldService::DeviceState {};
#endif

std::string FieldRequest::key() const {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%u/ds%d/%s/%s/%g..%g/b%g/p%d%s/%s", unsigned(label), params.downsample,
                toString(params.rule), toString(params.weight), double(params.huMin), double(params.huMax),
                double(params.baseCost), params.passes, params.converge ? "c" : "", toString(params.backend));
  return buf;
}

FieldService::FieldService(const Volume& volume, const LabelMap& labels, std::size_t capacity)
    : volume_(volume), labels_(labels), capacity_(capacity < 1 ? 1 : capacity), thread_([this] { run(); }) {}

FieldService::~FieldService() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
    queued_.reset();
    cancelRunning_ = true;
  }
  wake_.notify_all();
  changed_.notify_all();
  thread_.join();
}

void FieldService::request(const FieldRequest& request) {
  const std::string key = request.key();
  {
    std::lock_guard lock(mutex_);
    for (const auto& entry : lru_)
      if (entry.key == key) return;
    if (runningKey_ && *runningKey_ == key) {
      queued_.reset();  // the running one is what the user wants now
      runningPrefetch_ = false;  // a prefetch of it becomes the request
      return;
    }
    std::erase_if(prefetches_, [&](const FieldRequest& r) { return r.key() == key; });
    if (runningKey_) {
      // A prefetch cancelled for the request is tried again once the service is idle.
      if (!cancelRunning_.exchange(true) && runningPrefetch_) prefetches_.push_front(*runningRequest_);
    }
    queued_ = request;
  }
  wake_.notify_all();
}

void FieldService::cancelAll() {
  std::lock_guard lock(mutex_);
  queued_.reset();
  if (runningKey_ && !runningPrefetch_) cancelRunning_ = true;
}

void FieldService::prefetch(const std::vector<FieldRequest>& requests) {
  {
    std::lock_guard lock(mutex_);
    prefetches_.clear();
    pinned_.clear();
    for (const FieldRequest& r : requests) pinned_.push_back(r.key());
    bool runningListed = false;
    for (const FieldRequest& r : requests) {
      const std::string key = r.key();
      if (runningKey_ && *runningKey_ == key) {
        runningListed = true;
        continue;
      }
      const bool cached = std::any_of(lru_.begin(), lru_.end(), [&](const Entry& e) { return e.key == key; });
      const bool listed = std::any_of(prefetches_.begin(), prefetches_.end(), [&](const FieldRequest& p) { return p.key() == key; });
      if (!cached && !listed) prefetches_.push_back(r);
    }
    if (runningPrefetch_ && !runningListed) cancelRunning_ = true;  // no longer expected
  }
  wake_.notify_all();
}

void FieldService::holdPrefetches(bool hold) {
  {
    std::lock_guard lock(mutex_);
    if (prefetchesHeld_ == hold) return;
    prefetchesHeld_ = hold;
  }
  if (!hold) wake_.notify_all();
}

bool FieldService::computing(const FieldRequest& request) const {
  const std::string key = request.key();
  std::lock_guard lock(mutex_);
  return runningKey_ && *runningKey_ == key;
}

bool FieldService::prefetching() const {
  std::lock_guard lock(mutex_);
  return runningPrefetch_ || !prefetches_.empty();
}

void FieldService::updateLabels(const std::function<void()>& write, const std::vector<std::uint16_t>& changed) {
  std::unique_lock lock(mutex_);
  if (runningKey_) {
    cancelRunning_ = true;
    // The worker takes its next job under the mutex, so none starts until `write` is done.
    changed_.wait(lock, [&] { return !runningKey_.has_value(); });
  }
  write();
  lru_.remove_if([&](const Entry& e) { return std::find(changed.begin(), changed.end(), e.label) != changed.end(); });
  deviceLabelsStale_ = true;
}

FieldService::Cached FieldService::cached(const FieldRequest& request) {
  const std::string key = request.key();
  std::lock_guard lock(mutex_);
  for (auto it = lru_.begin(); it != lru_.end(); ++it)
    if (it->key == key) {
      lru_.splice(lru_.begin(), lru_, it);
      return {lru_.front().field, lru_.front().deviceField};
    }
  return {};
}

FieldService::Cached FieldService::waitFor(const FieldRequest& request, std::chrono::milliseconds limit) {
  const std::string key = request.key();
  std::unique_lock lock(mutex_);
  const auto cachedReady = [&] {
    for (const auto& entry : lru_)
      if (entry.key == key) return entry.field || entry.deviceField;
    return false;
  };
  const auto pending = [&] { return (queued_ && queued_->key() == key) || (runningKey_ && *runningKey_ == key); };
  changed_.wait_for(lock, limit, [&] { return stop_ || cachedReady() || !pending(); });
  for (auto it = lru_.begin(); it != lru_.end(); ++it)
    if (it->key == key) {
      lru_.splice(lru_.begin(), lru_, it);
      return {lru_.front().field, lru_.front().deviceField};
    }
  return {};
}

std::vector<FinishedField> FieldService::takeFinished() {
  std::lock_guard lock(mutex_);
  return std::exchange(finished_, {});
}

bool FieldService::busy() const {
  std::lock_guard lock(mutex_);
  return (runningKey_.has_value() && !runningPrefetch_) || queued_.has_value();
}

std::optional<FieldService::Running> FieldService::running() const {
  std::lock_guard lock(mutex_);
  if (!runningRequest_ || runningPrefetch_) return std::nullopt;
  Running r;
  r.request = *runningRequest_;
  r.passesDone = passesDone_.load();
  r.passesPlanned = passesPlanned_.load();
  if (r.passesPlanned == 0) r.passesPlanned = r.request.params.converge ? r.request.params.maxPasses : r.request.params.passes;
  r.elapsedMs = msSince(runningSince_);
  return r;
}

void FieldService::insert(Entry entry) {
  lru_.push_front(std::move(entry));
  const auto isPinned = [&](const Entry& e) { return std::find(pinned_.begin(), pinned_.end(), e.key) != pinned_.end(); };
  while (lru_.size() > capacity_) {
    // The least recently used entry that is not on the prefetch list, never the one just put in
    // (it is what someone is waiting for); the least recently used of all when every other is.
    auto victim = std::prev(lru_.end());
    for (auto it = std::prev(lru_.end()); it != lru_.begin(); --it)
      if (!isPinned(*it)) {
        victim = it;
        break;
      }
    lru_.erase(victim);
  }
  changed_.notify_all();
}

void FieldService::finishRunning() {
  runningPrefetch_ = false;
  runningKey_.reset();
  runningRequest_.reset();
  changed_.notify_all();
}

void FieldService::run() {
  for (;;) {
    FieldRequest job;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stop_ || queued_.has_value() || (!prefetches_.empty() && !prefetchesHeld_); });
      if (stop_) return;
      if (queued_) {
        job = *queued_;
        queued_.reset();
        runningPrefetch_ = false;
      } else {
        job = prefetches_.front();
        prefetches_.pop_front();
        const std::string key = job.key();
        if (std::any_of(lru_.begin(), lru_.end(), [&](const Entry& e) { return e.key == key; })) continue;
        runningPrefetch_ = true;
      }
      runningKey_ = job.key();
      runningRequest_ = job;
      runningSince_ = std::chrono::steady_clock::now();
      passesDone_ = 0;
      passesPlanned_ = 0;
      cancelRunning_ = false;
    }
    WdtControl control;
    control.cancel = &cancelRunning_;
    control.progress = [this](int done, int planned) {
      passesDone_ = done;
      passesPlanned_ = planned;
    };
    std::string warning = std::exchange(deviceWarning_, "");  // a host copy that failed last time
    Result<Outcome> outcome = detail::withCpuFallback<Outcome>(
        job.params.backend, [&] { return computeOnDevice(job, control); }, [&] { return computeOnCpu(job, control); },
        warning, &deviceBroken_);
    std::lock_guard lock(mutex_);
    if (outcome && outcome->cancelled) {
      cancelled_.fetch_add(1);  // stale: a newer request replaced it
    } else if (!outcome || !outcome->published) {
      FinishedField done = outcome ? std::move(outcome->finished) : FinishedField{};
      done.request = job;
      if (!outcome) done.message = outcome.error().message;
      else if (!warning.empty()) done.message = warning;
      done.prefetched = runningPrefetch_;
      if (done.field) insert({job.label, *runningKey_, done.field, nullptr});
      finished_.push_back(std::move(done));
    }
    finishRunning();
  }
}

Result<FieldService::Outcome> FieldService::computeOnCpu(const FieldRequest& job, const WdtControl& control) {
  WdtParams params = job.params;
  params.backend = WdtBackend::Cpu;
  auto result = computeWdt(volume_, structureMask(labels_, job.label), params, control);
  if (!result) return tl::unexpected(withContext("label " + std::to_string(job.label), result.error()));
  Outcome outcome;
  if (result->stats.cancelled) {
    outcome.cancelled = true;
    return outcome;
  }
  outcome.finished.field = std::make_shared<const DistanceField>(std::move(result->field));
  outcome.finished.ms = result->stats.msTotal;
  outcome.finished.device = result->stats.device;
  outcome.finished.message = result->stats.warning;
  return outcome;
}

Result<FieldService::Outcome> FieldService::computeOnDevice(const FieldRequest& job, const WdtControl& control) {
#if defined(AT_HAVE_CUDA)
  if (!device_) device_ = std::make_unique<DeviceState>();
  DeviceState& d = *device_;
  const auto t0 = std::chrono::steady_clock::now();
  {
    std::lock_guard lock(mutex_);
    if (std::exchange(deviceLabelsStale_, false)) d.volume.reset();  // edited labels: uploaded again
  }
  if (!d.volume) {
    auto uploaded = cuda::uploadVolume(volume_, labels_);
    if (!uploaded) return tl::unexpected(uploaded.error());
    d.volume = std::move(*uploaded);
  }
  WdtStats stats;
  auto field = cuda::runCudaBackendOnDevice(*d.volume, job.label, job.params, control, &stats);
  if (!field) {
    d.volume.reset();
    return tl::unexpected(field.error());
  }
  Outcome outcome;
  if (stats.cancelled) {
    outcome.cancelled = true;
    return outcome;
  }
  // Published at once: the view shows the device field through interop while the host copy,
  // which only picking reads, is still being made.
  const std::string key = job.key();
  auto device = std::make_shared<const cuda::DeviceField>(std::move(*field));
  FinishedField done;
  done.request = job;
  done.deviceField = device;
  done.ms = msSince(t0);
  done.device = stats.device;
  {
    std::lock_guard lock(mutex_);
    insert({job.label, key, nullptr, device});
    finished_.push_back(std::move(done));
  }
  auto host = std::make_shared<DistanceField>();
  host->downsample = device->downsample();
  // Fresh memory on huge pages: 4 KiB page faults would cost more than the copy (~40 ms at 256³).
  resizeOnHugePages(host->distances.voxels, device->grid().dims.count());
  const Status copied = cuda::copyToHost(*device, host->distances);
  {
    std::lock_guard lock(mutex_);
    for (auto it = lru_.begin(); it != lru_.end(); ++it) {
      if (it->key != key || it->deviceField != device) continue;
      if (copied) it->field = std::move(host);
      else lru_.erase(it);  // without a host copy the entry is dropped and recomputed on the CPU
      break;
    }
  }
  if (!copied) {
    deviceBroken_ = true;
    d.volume.reset();
    deviceWarning_ = "CUDA backend failed, computed on the CPU instead: " + copied.error().message;
  }
  outcome.published = true;
  return outcome;
#else
  (void)job;
  (void)control;
  return fail(ErrorKind::Unavailable, "WDT: this build has no CUDA backend");
#endif
}

}  // namespace at::wdt
